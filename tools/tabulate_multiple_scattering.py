#!/usr/bin/env python3
"""Tabulate multiple scattering (two or more events) of a semi-infinite slab by volumetric Monte Carlo, for the
``multiple_fit`` diffusion profile (reflets/translucency/multiple_fit.py).

Per relative index η and reduced albedo α' (isotropic scattering, lengths in reduced mean free paths 1/σ'_t), a
collimated beam enters the medium; photons that leave after exactly one event are single scattering (the
technique's own term), the others are tallied:

- ``energy[η, α']``: multiple-scattering exitance per unit transmitted flux, normal incidence;
- ``cdf[η, α', k]``: its radial cumulative distribution at the bin edges ``edges`` (normal incidence);
- ``incidence[η, α', μ]``: exitance at outside incidence cosine μ relative to normal incidence.

The same process as reflets.reference.volumetric.slab_reflectance (absorption weighting, Fresnel reflection from
inside, Russian roulette), with radial tallies. The albedo grid is uniform in u = sqrt(1 − α'), the variable
diffusion theory's energies are smooth in. At α' = 1 (no absorption) walks are capped; every photon leaves
eventually, so the energy there is set to 1 − single scattering and the capped walks only shape the profile.

Run: ``.venv/bin/python tools/tabulate_multiple_scattering.py`` (about 30 minutes on one shared core) → writes
src/reflets/data/translucency/multiple_scattering.npz.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from reflets.reference.volumetric import slab_reflectance
from reflets.translucency.medium import Medium

ETAS = (1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.7, 2.0)
U = (0.0, 0.01, 0.02, 0.035, 0.05, 0.07, 0.1, 0.14, 0.2, 0.27, 0.35, 0.45, 0.55, 0.65, 0.75, 0.85, 0.95, 0.99)
#: the rows in the shipped file (a 30-minute run on a shared core); multiple_fit clamps η to their range, and its
#: energy, interpolated as a ratio to the better dipole's total, carries the better dipole's η dependence beyond
SHIPPED = (1.0, 1.3, 1.5, 1.1)
COSINES = (1.0, 0.75, 0.5, 0.3, 0.15, 0.05)
EDGES = np.concatenate([[0.0], np.geomspace(0.005, 500.0, 76)])
OUT = Path(__file__).resolve().parents[1] / "src/reflets/data/translucency/multiple_scattering.npz"


def simulate(albedo, eta, photons, cos_incidence=1.0, seed=0, radial=False, max_events=30_000, chunk=100_000):
    """(single, multiple) exitance per transmitted photon and the multiple scattering's radial histogram, lengths
    in mean free paths (σ_t = 1), isotropic scattering: ``reference.volumetric.slab_reflectance``'s walk."""
    medium = Medium(np.float64(1.0 - albedo), np.float64(albedo), 0.0, float(eta))
    result = slab_reflectance(medium, photons, cos_incidence=cos_incidence, seed=seed, chunk=chunk,
                              max_events=max_events, radial_edges=EDGES if radial else None)  # fmt: skip
    hist = result.radial if radial else np.zeros(len(EDGES) - 1)
    return np.array([result.single, result.multiple]), hist


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--photons", type=int, default=200_000, help="per (η, α') for the radial profile")
    parser.add_argument("--incidence-photons", type=int, default=50_000, help="per (η, α', μ)")
    parser.add_argument(
        "--etas",
        type=float,
        nargs="+",
        choices=ETAS,
        default=SHIPPED,
        help="indices to tabulate (seeds follow each one's place in ETAS, so a subset reproduces its rows)",
    )
    parser.add_argument("-o", "--output", type=Path, default=OUT)
    args = parser.parse_args()
    energy = np.zeros((len(ETAS), len(U)))
    single = np.zeros_like(energy)
    cdf = np.zeros((len(ETAS), len(U), len(EDGES)))
    incidence = np.ones((len(ETAS), len(U), len(COSINES)))
    done: list[int] = []
    start = time.perf_counter()
    for eta in args.etas:  # in this order; the file is saved after each
        i = ETAS.index(eta)
        for j, u in enumerate(U):
            albedo = 1.0 - u * u
            seed = 1000 * i + j
            (ss, ms), hist = simulate(albedo, eta, args.photons, seed=seed, radial=True)
            if u == 0.0:
                ms = 1.0 - ss  # no absorption: every transmitted photon leaves (capped walks only shape R(r))
            energy[i, j], single[i, j] = ms, ss
            cdf[i, j, 1:] = np.cumsum(hist) / max(hist.sum(), 1e-300)
            for k, mu in enumerate(COSINES[1:], start=1):
                if u == 0.0:  # every photon leaves: 1 − single scattering, which the first events decide
                    (ss_mu, _), _ = simulate(albedo, eta, args.incidence_photons, mu, seed=seed + k, max_events=3)
                    incidence[i, j, k] = (1.0 - ss_mu) / ms
                    continue
                (_, ms_mu), _ = simulate(albedo, eta, args.incidence_photons, mu, seed=seed + 100_000 * k)
                incidence[i, j, k] = ms_mu / ms if ms > 0 else 1.0
            seconds = time.perf_counter() - start
            print(f"η {eta:.2f} α' {albedo:.5f}: single {ss:.4f} multiple {ms:.4f} ", end="")
            print(f"incidence {np.round(incidence[i, j], 3)}  {seconds:.0f} s", flush=True)
        done.append(i)
        save(args, sorted(done), energy, single, cdf, incidence)


def save(args, done, energy, single, cdf, incidence) -> None:
    """The rows of the indices of refraction ``done`` so far (a long run is usable before it ends)."""
    args.output.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        args.output,
        eta=np.array(ETAS)[done],
        u=np.array(U),
        cosines=np.array(COSINES),
        edges=EDGES,
        energy=energy[done],
        single=single[done],
        cdf=cdf[done].astype(np.float32),
        incidence=incidence[done],
        photons=np.array([args.photons, args.incidence_photons]),
    )
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
