from __future__ import annotations


def test_docs_brdfs_page_is_generated_from_the_docstrings():
    """docs/brdfs.md must be regenerated (python -m reflets.brdf.docs > docs/brdfs.md) when a model changes."""
    from pathlib import Path

    from reflets.brdf.docs import markdown

    page = Path(__file__).parents[2] / "docs" / "brdfs.md"
    assert page.read_text(encoding="utf-8") == markdown()
