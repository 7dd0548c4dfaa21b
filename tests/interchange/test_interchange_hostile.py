"""An imported SpaceEx file is untrusted: hostile XML is refused quickly, with a position.

Billion laughs, external entities (general and parameter, file and network),
oversized files, deep nesting and malformed XML each end in one
``file:line:column: message`` SpecError; nothing is fetched (a loopback
server counts requests) and nothing is expanded.
"""

from __future__ import annotations

import http.server
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from support import run_cli

import hybrid
from hybrid.interchange import import_spaceex, safexml
from hybrid.interchange.safexml import (
    MAX_XML_BYTES,
    MAX_XML_DEPTH,
    MAX_XML_ELEMENTS,
    parse_xml_bytes,
)

BILLION_LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE lolz [
 <!ENTITY lol "lol">
 <!ENTITY lol1 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
 <!ENTITY lol2 "&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;">
 <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
 <!ENTITY lol9 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
]>
<sspaceex><component id="c"><note>&lol9;</note></component></sspaceex>
"""


@pytest.fixture
def server() -> Iterator[tuple[str, list[str]]]:
    """A loopback HTTP server recording every path asked of it."""
    asked: list[str] = []

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            asked.append(self.path)
            self.send_response(200)
            self.end_headers()
            self.wfile.write(b'<!ENTITY x "fetched">')

        def log_message(self, *args: object) -> None:
            pass

    httpd = http.server.HTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=httpd.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}", asked
    httpd.shutdown()
    httpd.server_close()


def _refused(raw: bytes, tmp_path: Path) -> hybrid.SpecError:
    path = tmp_path / "MODEL.xml"
    path.write_bytes(raw)
    with pytest.raises(hybrid.SpecError) as info:
        import_spaceex(path)
    assert info.value.file == str(path)
    return info.value


def test_billion_laughs_is_refused_at_the_doctype(tmp_path: Path) -> None:
    err = _refused(BILLION_LAUGHS.encode(), tmp_path)
    assert (err.line, err.column) == (2, 1)  # where '<!DOCTYPE' is written
    assert "document type declaration" in err.message


@pytest.mark.parametrize(
    "doctype",
    [
        '<!DOCTYPE s [<!ENTITY x SYSTEM "{url}/general">]>',
        '<!DOCTYPE s [<!ENTITY % p SYSTEM "{url}/parameter"> %p;]>',
        '<!DOCTYPE s SYSTEM "{url}/dtd">',
        '<!DOCTYPE s [<!ENTITY x SYSTEM "file:///etc/passwd">]>',
    ],
    ids=["general", "parameter", "external-dtd", "file"],
)
def test_external_entities_are_refused_and_nothing_is_fetched(
    doctype: str, server: tuple[str, list[str]], tmp_path: Path
) -> None:
    url, asked = server
    raw = f'<?xml version="1.0"?>\n{doctype.format(url=url)}\n<s><c>&x;</c></s>\n'.encode()
    err = _refused(raw, tmp_path)
    assert (err.line, err.column) == (2, 1)
    assert asked == []


def test_an_undeclared_entity_is_malformed_not_fetched(tmp_path: Path) -> None:
    err = _refused(b"<sspaceex>\n  <component id='a'>&x;</component></sspaceex>", tmp_path)
    assert (err.line, err.column) == (2, 21)
    assert err.message == "malformed XML: undefined entity"


def test_a_50_mb_file_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / "MODEL.xml"
    with path.open("wb") as handle:  # sparse: nothing to read even if one tried
        handle.truncate(50 * 1024 * 1024)
    with pytest.raises(hybrid.SpecError) as info:
        import_spaceex(path)
    assert (info.value.line, info.value.column) == (1, 1)
    assert f"over the limit of {MAX_XML_BYTES} bytes: refused unread" in info.value.message


def test_a_large_string_is_refused_before_parsing() -> None:
    with pytest.raises(hybrid.SpecError, match="over the limit"):
        parse_xml_bytes(b"<a>" + b" " * (MAX_XML_BYTES + 1) + b"</a>", "big.xml")


def test_deep_nesting_is_refused_at_the_element(tmp_path: Path) -> None:
    raw = b"<a>" * (MAX_XML_DEPTH + 10) + b"</a>" * (MAX_XML_DEPTH + 10)
    err = _refused(raw, tmp_path)
    assert (err.line, err.column) == (1, 3 * MAX_XML_DEPTH + 1)  # the 65th '<a>'
    assert "nested more than" in err.message


def test_too_many_elements_are_refused_before_any_node_is_built(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """1.2 million empty elements (4.8 MB, under the size cap): refused at the one past the cap.

    The bound is on work, not time: no node is built, and the memory traced is
    about the file's bytes (building the nodes up to the cap took 495 MB).
    """
    import tracemalloc

    built: list[int] = []
    start = safexml._Builder.start
    monkeypatch.setattr(safexml._Builder, "start",
                        lambda self, tag, attrs: (built.append(1), start(self, tag, attrs)))  # fmt: skip
    raw = b"<sspaceex>" + b"<p/>" * (MAX_XML_ELEMENTS + 200_000) + b"</sspaceex>"
    tracemalloc.start()
    try:
        err = _refused(raw, tmp_path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert "more than 1000000 elements" in err.message
    # the root is element 1: element 1,000,001 is the 1,000,000th '<p/>', at 10 + 4 * 999,999 + 1
    assert (err.line, err.column) == (1, 10 + 4 * (MAX_XML_ELEMENTS - 1) + 1)
    assert built == []
    assert peak < 4 * len(raw), f"{peak / 1e6:.1f} MB traced for a {len(raw) / 1e6:.1f} MB file"


def test_a_file_under_the_element_cap_is_parsed_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    counted: list[int] = []
    monkeypatch.setattr(safexml, "_refuse_too_many_elements", lambda *a: counted.append(1))
    root = parse_xml_bytes(b"<sspaceex>" + b"<p/>" * 1000 + b"</sspaceex>", "m.xml")
    assert len(root.children) == 1000 and counted == []


@pytest.mark.parametrize(
    ("raw", "line", "column", "message"),
    [
        (b"<sspaceex>\n<component id='a'>\n</sspaceex>", 3, 3, "mismatched tag"),
        (b"<sspaceex><component id='a' id='b'/></sspaceex>", 1, 29, "duplicate attribute"),
        (b"<sspaceex/>\n<other/>", 2, 1, "junk after document element"),
        (b"<sspaceex>", 1, 11, "no element found"),
        (b"", 1, 1, "no element found"),
        (b"\x00\x01binary", 1, 1, "not well-formed (invalid token)"),
        (b"<sspaceex><c x=1/></sspaceex>", 1, 16, "not well-formed (invalid token)"),
    ],
    ids=[
        "mismatched",
        "duplicate-attribute",
        "two-roots",
        "unclosed",
        "empty",
        "binary",
        "unquoted",
    ],
)
def test_malformed_xml_is_refused_with_expats_position(
    raw: bytes, line: int, column: int, message: str, tmp_path: Path
) -> None:
    err = _refused(raw, tmp_path)
    assert (err.line, err.column) == (line, column)
    assert err.message == f"malformed XML: {message}"


def test_columns_count_characters_not_bytes(tmp_path: Path) -> None:
    raw = "<sspaceex><note>ééé</note><c a='1' a='2'/></sspaceex>".encode()
    err = _refused(raw, tmp_path)
    assert err.column == len("<sspaceex><note>ééé</note><c a='1' ") + 1


def test_the_command_line_refuses_hostile_xml_with_exit_2_and_no_traceback(
    tmp_path: Path,
) -> None:
    path = tmp_path / "MODEL.xml"
    path.write_text(BILLION_LAUGHS)
    done = run_cli("import", "spaceex", path, "--out", tmp_path / "out")
    assert done.returncode == 2
    assert done.stderr.startswith(f"{path}:2:1: a document type declaration")
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()


def test_columns_count_characters_in_latin_1_files_too(tmp_path: Path) -> None:
    raw = "<?xml version='1.0' encoding='iso-8859-1'?>\n<s><n>ééé</n><c a='1' a='2'/></s>"
    err = _refused(raw.encode("latin-1"), tmp_path)
    assert (err.line, err.column) == (2, len("<s><n>ééé</n><c a='1' ") + 1)


def test_a_doctype_after_non_ascii_text_is_placed_in_characters(tmp_path: Path) -> None:
    err = _refused("<!-- é -->\n  <!DOCTYPE s []><s/>".encode(), tmp_path)
    assert (err.line, err.column) == (2, 3)
