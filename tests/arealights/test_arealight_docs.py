from __future__ import annotations


def test_area_lights_page_is_generated_from_the_method_docstrings():
    """Regenerate with: python -m reflets.arealights.docs > docs/techniques/area-lights.md"""
    from pathlib import Path

    from reflets.arealights.docs import markdown

    page = Path(__file__).parents[2] / "docs" / "techniques" / "area-lights.md"
    assert page.read_text(encoding="utf-8") == markdown()
