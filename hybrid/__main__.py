"""``python -m hybrid``: the command line."""

from hybrid.cli.main import main

raise SystemExit(main())
