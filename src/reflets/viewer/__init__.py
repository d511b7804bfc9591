"""The interactive viewer: one controller (camera, selection, edits, accumulation, overlays) shared by the
desktop window (``reflets view``) and the Jupyter widget (``reflets.Viewer``)."""

from .camera import OrbitCamera
from .controller import ViewerController

__all__ = ["OrbitCamera", "ViewerController"]
