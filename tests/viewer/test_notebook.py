"""``reflets.Viewer`` in Jupyter: docs/notebooks/viewer.ipynb executed by nbclient in a fresh kernel — it creates
a viewer, sends the browser's events (a drag), checks ``snapshot()`` against a one-shot render and edits a
material (the notebook's own asserts are the checks)."""

from __future__ import annotations

from pathlib import Path

import pytest

NOTEBOOK = Path(__file__).resolve().parents[2] / "docs" / "notebooks" / "viewer.ipynb"


@pytest.mark.slow
def test_the_viewer_notebook_runs(tmp_path):
    import nbclient
    import nbformat

    notebook = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(
        notebook, timeout=300, kernel_name="python3", resources={"metadata": {"path": tmp_path}}
    )
    client.execute()
    printed = "".join(o.get("text", "") for o in notebook.cells[-1].outputs if o.get("output_type") == "stream")
    selection, change = printed.rsplit(" ", 1)
    assert selection.startswith("mesh[0]") and float(change) > 1.0  # the edit shows
