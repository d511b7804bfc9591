"""Scratch profiles: analytic shapes, tabulated height fields (CSV / NumPy), periodic closing, spec strings."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.errors import ArgumentError
from reflets.scratches import from_samples, parse_profile, quartic, read_profile, vgroove


def test_vgroove_knots_lid_and_wall_slope():
    p = parse_profile("vgroove:0.5")
    assert p.kind == "polyline" and p.cells == 2
    np.testing.assert_allclose(p.height([0.0, 0.25, 0.5, 0.75, 1.0]), [0.0, -0.25, -0.5, -0.25, 0.0])
    assert p.lid == 0.0 and p.bottom == -0.5
    np.testing.assert_allclose(np.abs(p.slopes), 1.0)  # right-angle V: walls at 45°
    assert p.symmetric
    assert parse_profile("vgroove:0.866").max_slope == pytest.approx(np.tan(np.radians(60.0)), rel=1e-3)


def test_quartic_formula_documented():
    d = 0.8
    p = quartic(d)
    x = np.linspace(0.0, 1.0, 10001)
    s = 2 * x - 1
    np.testing.assert_allclose(p.height(x), -d * (1 - s * s) ** 2, atol=1e-15)
    assert p.height(0.5) == pytest.approx(-d) and p.height(0.0) == 0.0 and p.height(1.0) == 0.0
    slope = p.slope(x)
    np.testing.assert_allclose(slope[[0, 5000, -1]], 0.0, atol=1e-12)  # flat rims and bottom
    np.testing.assert_allclose(np.gradient(p.height(x), x)[1:-1], slope[1:-1], atol=2e-4)
    assert np.abs(slope).max() == pytest.approx(p.max_slope, rel=1e-6)
    assert p.symmetric and p.lid == 0.0


def test_table_formats_give_the_same_normalised_profile(tmp_path):
    x = np.linspace(0.0, 20.0, 41)  # micrometres, say
    h = -3.0 * np.sin(np.pi * x / 20.0) ** 2 + 0.5 * np.sin(2 * np.pi * x / 20.0)  # asymmetric, h(0) = h(20)
    csv = tmp_path / "p.csv"
    csv.write_text("# profilometer export\nx,h\n" + "\n".join(f"{a},{b}" for a, b in zip(x, h, strict=True)))
    np.save(tmp_path / "p.npy", np.stack([x, h], axis=1))
    np.savez(tmp_path / "p.npz", x=x, h=h)
    profiles = [read_profile(csv), parse_profile(f"file:{tmp_path / 'p.npy'}"), read_profile(tmp_path / "p.npz")]
    for p in profiles:
        np.testing.assert_allclose(p.x, x / 20.0, atol=1e-15)
        np.testing.assert_allclose(p.h, h / 20.0, atol=1e-15)  # same aspect ratio, width 1
        assert not p.symmetric
    # scale invariance: the same shape in other units is the same profile
    q = from_samples(x * 1e-3, h * 1e-3)
    np.testing.assert_allclose(q.h, profiles[0].h, atol=1e-15)


def test_open_table_is_closed_periodically_and_lid_is_its_highest_point():
    x = np.arange(5.0)
    h = np.array([0.0, -2.0, 1.0, -1.0, 0.5])  # rises above the base, last ≠ first
    p = from_samples(x, h)
    assert p.cells == 5  # one closing segment of the mean spacing
    np.testing.assert_allclose(p.x, np.arange(6) / 5.0)
    np.testing.assert_allclose(p.h, np.append(h, 0.0) / 5.0)
    assert p.lid == pytest.approx(1.0 / 5.0)
    np.testing.assert_allclose(p.height([0.1, 1.1, -0.9]), p.height(0.1))  # periodic


@pytest.mark.parametrize(
    ("spec", "match"),
    [
        ("vgroove", "vgroove:DEPTH"),
        ("vgroove:deep", "DEPTH a number"),
        ("quartic:-1", "≥ 0"),
        ("sphere:1", "unknown profile"),
        ("file:", "needs a path"),
        ("file:/nonexistent/p.csv", "not found"),
    ],
)
def test_bad_specs_are_one_line_argument_errors(spec, match):
    with pytest.raises(ArgumentError, match=match) as info:
        parse_profile(spec)
    assert "\n" not in str(info.value)


def test_bad_table_files(tmp_path):
    one = tmp_path / "one.csv"
    one.write_text("1\n2\n3\n")
    with pytest.raises(ArgumentError, match="two numeric columns"):
        read_profile(one)
    dup = tmp_path / "dup.npy"
    np.save(dup, np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]))
    with pytest.raises(ArgumentError, match="distinct"):
        read_profile(dup)
    with pytest.raises(ArgumentError, match="knots must increase"):
        vgroove(0.5).__class__("bad", np.array([0.0, 0.7, 0.5, 1.0]), np.zeros(4))
