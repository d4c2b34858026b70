"""The files a user of a scientific package looks for at the top: LICENSE, CHANGELOG.md and CITATION.cff, the
citation file valid against the Citation File Format 1.2.0 schema (cffconvert's validator, offline: the schema ships
inside the package) and consistent with pyproject.toml."""
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
cffconvert = pytest.importorskip("cffconvert", reason="pip install 'cubedimer[test]' (cffconvert validates CITATION.cff)")


def _pyproject() -> dict:
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        tomllib = pytest.importorskip("tomli")
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


def _validate(text: str) -> None:
    cffconvert.Citation(text).validate()


def test_citation_file_is_valid_cff_1_2_0_and_cites_the_source_paper():
    text = (ROOT / "CITATION.cff").read_text()
    assert re.search(r"^cff-version: 1\.2\.0$", text, re.MULTILINE)
    _validate(text)  # raises on any schema violation
    for author in ("Xia", "Lim", "Kim", "VanSaders", "Jaeger"):
        assert f"family-names: {author}\n" in text, author
    assert "10.48550/arXiv.2603.15894" in text


def test_the_validator_rejects_a_broken_citation_file():
    """The check above can fail: the same file without its required authors, or with a malformed DOI, is refused."""
    text = (ROOT / "CITATION.cff").read_text()
    no_authors = re.sub(r"^authors:\n(  - .*\n)+", "", text, count=1, flags=re.MULTILINE)
    assert no_authors != text
    bad_doi = text.replace("doi: 10.48550/arXiv.2603.15894", "doi: arXiv.2603.15894")
    for broken in (no_authors, bad_doi):
        with pytest.raises(Exception):
            _validate(broken)


def test_citation_licence_and_changelog_agree_with_pyproject():
    project = _pyproject()
    text = (ROOT / "CITATION.cff").read_text()
    assert re.search(rf"^version: {re.escape(project['version'])}$", text, re.MULTILINE)
    assert re.search(rf"^license: {re.escape(project['license'])}$", text, re.MULTILINE)
    assert project["license"] == "BSD-3-Clause" and "BSD 3-Clause License" in (ROOT / "LICENSE").read_text()
    assert f"## [{project['version']}]" in (ROOT / "CHANGELOG.md").read_text()
