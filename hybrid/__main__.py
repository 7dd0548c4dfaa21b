"""``python -m hybrid``: the command line."""

import sys

try:
    from hybrid.cli.main import entry
except KeyboardInterrupt:  # Ctrl-C while the command line itself is imported
    print("hybrid: interrupted", file=sys.stderr)
    raise SystemExit(130) from None

raise SystemExit(entry())
