"""Every whole-frame method, imported so that its ``@register_technique`` runs: the registry behind
``--method`` (``reflets.techniques.TECHNIQUES``) holds them all once ``reflets`` is imported."""

from .. import arealights  # noqa: F401  (brute, adaptive, biased, mc, analytic, ltc)
from ..reflections import technique as _fermat  # noqa: F401  (fermat)
from ..scratches import technique as _scratches  # noqa: F401  (scratches)
from ..techniques import forward  # noqa: F401  (forward, position, normal, uv)
from ..translucency import technique as _translucent  # noqa: F401  (translucent)
from . import compose  # noqa: F401  (auto)
