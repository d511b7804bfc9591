"""`reflets scratch-brdf`: writes the table and its plot; bad input exits 2 with one line and writes nothing."""

from __future__ import annotations

import numpy as np

from reflets.cli import main
from reflets.scratches import load_table


def test_writes_a_table_and_a_plot(tmp_path, capsys):
    out = tmp_path / "vgroove.npz"
    args = ["scratch-brdf", "--profile", "vgroove:0.5", "--conductor", "2.91", "3.09", "--size", "32"]
    assert main([*args, "--rays", "1000", "-o", str(out)]) == 0
    table = load_table(out)
    assert table.rho_m.shape == (32, 32) and table.phi.shape == (32,)
    dphi = np.pi / 32
    energy = np.sum(table.rho_m * np.cos(table.phi)[:, None] * dphi, axis=0)
    np.testing.assert_allclose(energy, 1.0, atol=1e-2)  # lossless ρ_m; the conductor only enters ρ_s
    assert np.all(table.rho_s0 <= table.rho_m + 1e-9)
    assert (tmp_path / "vgroove.png").stat().st_size > 1000
    assert "wrote" in capsys.readouterr().out


def test_bad_inputs_exit_2(tmp_path, capsys):
    for argv in (
        ["--profile", "nope:1", "-o", str(tmp_path / "a.npz")],
        ["--profile", "vgroove:0.5", "-o", str(tmp_path / "a.txt")],
        ["--profile", "vgroove:0.5", "--conductor", "1", "2", "3", "-o", str(tmp_path / "a.npz")],
        ["--profile", "file:" + str(tmp_path / "missing.csv"), "-o", str(tmp_path / "a.npz")],
    ):
        capsys.readouterr()
        assert main(["scratch-brdf", *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "Traceback" not in err[0], err
    assert not any(tmp_path.iterdir())
