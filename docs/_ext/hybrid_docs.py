"""The Sphinx extension of the hybrid site: references generated from the code, figures drawn
at build time, the JSON Schema at a stable path.

- ``<!-- hybrid-docs:cli-reference -->`` in a page is replaced, when the page is
  read, by the reference of every command, generated from
  ``hybrid.cli.main.build_parser()``: it cannot drift from the parser.
- ``<!-- hybrid-docs:api-index -->`` is replaced by one table per module of
  ``API_MODULES`` (conf.py) listing every name of its ``__all__``; each name gets
  a page under ``api/`` (written when the build starts, documented by autodoc
  from its numpydoc docstring). A name exported by several modules is
  documented once, under the first.
- A ```` ```{hybrid-plot} ```` block holds Python code: the page shows it, runs it
  from the repository root and shows every new matplotlib figure the code binds to
  a name. The blocks of a page share one namespace (not with its ``python`` blocks,
  which the build does not run). An exception fails the build (a warning, and
  warnings are errors).
- ``<!-- hybrid-docs:notebook NAME.ipynb -->`` is replaced, when the page is read, by
  the notebook beside the page as it was executed and stored: its Markdown cells,
  its code, and its stored outputs (text as text, figures as images). The build
  does not run it; tests/docs/test_docs_notebooks.py does, and holds the stored
  outputs to what it prints.
- ``schema/automaton.schema.json`` is copied to ``<site>/schema/``.
- Mermaid fences are shown as text (the diagram renders on GitHub).
"""

from __future__ import annotations

import argparse
import base64
import importlib
import json
import os
import re
import shutil
import traceback
from collections.abc import Iterator
from pathlib import Path
from typing import Any, ClassVar

from docutils import nodes
from docutils.parsers.rst import directives
from pygments.lexers.special import TextLexer
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

LOG = logging.getLogger(__name__)
CLI_MARKER = "<!-- hybrid-docs:cli-reference -->"
API_MARKER = "<!-- hybrid-docs:api-index -->"
API_DIR = "api"
FIGURE_DIR = "_generated/figures"
NOTEBOOK_MARKER = re.compile(r"<!-- hybrid-docs:notebook (?P<name>[\w.-]+\.ipynb) -->")
NOTEBOOK_DIR = "_generated/notebooks"


# --- the command-line reference ----------------------------------------------------------


def _cell(text: object) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _usage(parser: argparse.ArgumentParser) -> str:
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "88"
    try:
        return parser.format_usage().strip()
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


def _argument(action: argparse.Action) -> tuple[str, str, str]:
    if action.option_strings:
        metavar = action.metavar or (action.dest.upper() if action.nargs != 0 else "")
        name = ", ".join(action.option_strings) + (f" {metavar}" if metavar else "")
    else:
        name = str(action.metavar or action.dest)
    if action.required or not action.option_strings:
        default = "required"
    elif action.nargs == 0 or action.default in (None, [], argparse.SUPPRESS):
        default = ""
    else:
        default = f"`{action.default}`"
    meaning = action.help or ""
    if action.choices:
        meaning = (
            (meaning + "; " if meaning else "")
            + "one of "
            + ", ".join(f"`{c}`" for c in action.choices)
        )
    if action.nargs in ("+", "*") and not action.option_strings:
        meaning = (meaning + "; " if meaning else "") + "one or more"
    if isinstance(action, argparse._AppendAction):
        meaning = (meaning + "; " if meaning else "") + "repeatable"
    return f"`{name}`", default, meaning


def cli_reference() -> str:
    """Markdown of every ``hybrid`` command, from the argparse parser."""
    from hybrid.cli.main import build_parser

    parser = build_parser()
    out = [f"```text\n{_usage(parser)}\n```", "", parser.description or "", ""]
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {c.dest: c.help for c in sub._choices_actions}
    out += ["| command | does |", "|---|---|"]
    out += [
        f"| [`hybrid {name}`](#hybrid-{name}) | {_cell(helps.get(name, ''))} |"
        for name in sub.choices
    ]
    for name, command in sub.choices.items():
        out += ["", f"## `hybrid {name}`", "", _cell(helps.get(name, "")), ""]
        out += [f"```text\n{_usage(command)}\n```", ""]
        rows = [_argument(a) for a in command._actions if not isinstance(a, argparse._HelpAction)]
        if rows:
            out += ["| argument | default | meaning |", "|---|---|---|"]
            out += [f"| {_cell(n)} | {_cell(d)} | {_cell(m)} |" for n, d, m in rows]
    return "\n".join(out) + "\n"


# --- the API reference -------------------------------------------------------------------


def api_entries(modules: list[str]) -> Iterator[tuple[str, list[tuple[str, Any]]]]:
    """``(module, [(name, object), ...])`` for each module; every object once."""
    seen: set[int] = set()
    for module_name in modules:
        module = importlib.import_module(module_name)
        names = []
        for name in getattr(module, "__all__", []):
            obj = getattr(module, name)
            if name.startswith("__") or id(obj) in seen:
                continue
            seen.add(id(obj))
            names.append((name, obj))
        yield module_name, names


def _kind(obj: Any) -> str:
    if isinstance(obj, type):
        return "class"
    if callable(obj):
        return "function"
    return "data"


def write_api_pages(app: Sphinx) -> None:
    """One page per public name under ``api/`` (generated: not in git)."""
    target = Path(app.srcdir) / API_DIR
    pages = {}
    for module, entries in api_entries(app.config.API_MODULES):
        for name, obj in entries:
            directive = {"class": "autoclass", "function": "autofunction", "data": "autodata"}
            kind = _kind(obj)
            options = "\n   :members:\n   :undoc-members:" if kind == "class" else ""
            pages[f"{module}.{name}.md"] = (
                f"# {module}.{name}\n\n```{{eval-rst}}\n.. currentmodule:: {module}\n\n"
                f".. {directive[kind]}:: {name}{options}\n```\n"
            )
    target.mkdir(exist_ok=True)
    for stale in target.glob("*.md"):
        if stale.name not in pages:
            stale.unlink()
    for filename, text in pages.items():
        path = target / filename
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")


def api_index(modules: list[str]) -> str:
    out = []
    for module, entries in api_entries(modules):
        doc = (importlib.import_module(module).__doc__ or "").strip().splitlines()
        out += [f"## `{module}`", "", doc[0] if doc else "", ""]
        if entries:
            out += ["```{eval-rst}", f".. currentmodule:: {module}", "", ".. autosummary::", ""]
            out += [f"   {name}" for name, _ in entries]
            out += ["```", ""]
    return "\n".join(out)


# --- figures drawn at build time ---------------------------------------------------------


class HybridPlot(SphinxDirective):
    """```{hybrid-plot}``` code: shown, run from the repository root, its figures shown."""

    has_content = True
    option_spec: ClassVar[dict[str, Any]] = {
        "alt": directives.unchanged,
        "hide-code": directives.flag,
    }

    def run(self) -> list[nodes.Node]:
        code = "\n".join(self.content)
        result: list[nodes.Node] = []
        if "hide-code" not in self.options:
            block = nodes.literal_block(code, code)
            block["language"] = "python"
            result.append(block)
        root = Path(self.env.srcdir).parent
        namespace = self.env.temp_data.setdefault("hybrid_plot_namespace", {"__name__": "__docs__"})
        from matplotlib.figure import Figure

        shown = {id(v) for v in namespace.values() if isinstance(v, Figure)}
        cwd = Path.cwd()
        try:
            os.chdir(root)
            exec(compile(code, f"{self.env.docname}.md", "exec"), namespace)  # our own pages
        except Exception:
            LOG.warning(
                "hybrid-plot block failed:\n%s",
                traceback.format_exc(),
                location=self.get_location(),
            )
            return result
        finally:
            os.chdir(cwd)
        figures = [v for v in namespace.values() if isinstance(v, Figure) and id(v) not in shown]
        if not figures:
            LOG.warning("hybrid-plot block binds no figure to a name", location=self.get_location())
        out_dir = Path(self.env.srcdir) / FIGURE_DIR
        out_dir.mkdir(parents=True, exist_ok=True)
        serial = self.env.new_serialno("hybrid-plot")
        for k, fig in enumerate(figures):
            stem = f"{self.env.docname.replace('/', '-')}-{serial}-{k}.png"
            fig.savefig(out_dir / stem, dpi=90)
            uri = f"/{FIGURE_DIR}/{stem}"
            image = nodes.image(uri=uri, alt=self.options.get("alt", "figure"))
            result.append(image)
        return result


# --- notebooks ---------------------------------------------------------------------------


def _text(value: object) -> str:
    return "".join(value) if isinstance(value, list) else str(value)


def _fence(language: str, text: str) -> str:
    ticks = "`" * max([3, *(len(run) + 1 for run in re.findall(r"`{3,}", text))])
    return f"{ticks}{language}\n{text.rstrip()}\n{ticks}"


def notebook_markdown(srcdir: Path, docname: str, name: str) -> str:
    """The stored notebook ``name`` beside page ``docname``, as MyST Markdown."""
    path = (srcdir / docname).parent / name
    notebook = json.loads(path.read_text(encoding="utf-8"))
    out_dir = srcdir / NOTEBOOK_DIR
    out_dir.mkdir(parents=True, exist_ok=True)
    parts: list[str] = []
    for i, cell in enumerate(notebook["cells"]):
        source = _text(cell["source"])
        if cell["cell_type"] == "markdown":
            parts.append(source)
            continue
        if cell["cell_type"] != "code":
            continue
        parts.append(_fence("python", source))
        for k, output in enumerate(cell.get("outputs", [])):
            data = output.get("data", {})
            if output["output_type"] == "stream":  # a line redrawn after "\r": its last drawing
                lines = _text(output["text"]).split("\n")
                parts.append(_fence("text", "\n".join(ln.rsplit("\r", 1)[-1] for ln in lines)))
            elif "image/png" in data:
                stem = f"{path.stem}-{i}-{k}.png"
                (out_dir / stem).write_bytes(base64.b64decode(_text(data["image/png"])))
                parts.append(f"![output of the cell above](/{NOTEBOOK_DIR}/{stem})")
            elif "text/plain" in data:
                parts.append(_fence("text", _text(data["text/plain"])))
            elif output["output_type"] == "error":
                LOG.warning("notebook %s stores an error", path.name)
    return "\n\n".join(parts)


# --- wiring ------------------------------------------------------------------------------


def _source_read(app: Sphinx, docname: str, source: list[str]) -> None:
    if CLI_MARKER in source[0]:
        source[0] = source[0].replace(CLI_MARKER, cli_reference())
    if API_MARKER in source[0]:
        source[0] = source[0].replace(API_MARKER, api_index(app.config.API_MODULES))
    srcdir = Path(app.srcdir)
    source[0] = NOTEBOOK_MARKER.sub(
        lambda found: notebook_markdown(srcdir, docname, found["name"]), source[0]
    )


def _copy_schema(app: Sphinx, exception: BaseException | None) -> None:
    if exception is None and app.builder.format == "html":
        target = Path(app.outdir) / "schema"
        target.mkdir(exist_ok=True)
        for path in (Path(app.srcdir) / "schema").glob("*.json"):
            shutil.copyfile(path, target / path.name)


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_config_value("API_MODULES", [], "env")
    app.connect("builder-inited", write_api_pages)
    app.connect("source-read", _source_read)
    app.connect("build-finished", _copy_schema)
    app.add_directive("hybrid-plot", HybridPlot)
    app.add_lexer("mermaid", TextLexer)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
