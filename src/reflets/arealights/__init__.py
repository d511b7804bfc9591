"""Area lights with arbitrary BRDFs: the area-light document's methods, exact diffuse, and LTC.

Each module registers one method (``--method NAME``); see ``base.py`` for the shared machinery and
docs/techniques/area-lights.md for what each approximates and how accurate and fast it is.
"""

from . import adaptive, analytic, biased, brute, ltc, mc  # noqa: F401  (each registers its method)
