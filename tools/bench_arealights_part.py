"""Run a part of `reflets bench arealights` (the whole suite takes over half an hour on a 2-core llvmpipe host).

    python tools/bench_arealights_part.py OUT_DIR [--materials "phong e=150,ggx a=0.1"] [--settings "ltc,brute 8²"]

Same scene, reference, metrics and timing as the suite (reflets.bench.arealights.bench_arealights); writes
OUT_DIR/arealights-part.{json,md} and OUT_DIR/arealights.png, and prints the table. The defaults are the rows
that compare the `ltc` bases: ltc, ltc base=cosine and brute 8² for every material of both lists.
"""

import argparse
import sys
from pathlib import Path

from reflets import jsonio
from reflets.bench import machine
from reflets.bench.arealights import MATERIALS, TABLE_MATERIALS, bench_arealights


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir", type=Path)
    every = ",".join([*MATERIALS, *TABLE_MATERIALS])
    parser.add_argument("--materials", default=every, help="comma-separated MATERIALS / TABLE_MATERIALS labels")
    parser.add_argument("--settings", default="ltc,ltc base=cosine,brute 8²", help="comma-separated SETTINGS labels")
    args = parser.parse_args(argv)
    args.out_dir.mkdir(parents=True, exist_ok=True)
    results, markdown = bench_arealights(
        False, args.out_dir, materials=args.materials.split(","), settings=args.settings.split(",")
    )
    info = machine()
    command = " ".join(["python tools/bench_arealights_part.py", *(f'"{a}"' if " " in a else a for a in sys.argv[1:])])
    markdown += f"\nMachine: {info['cores']} cores, {info['platform']}. Command: `{command}`.\n"
    jsonio.write(args.out_dir / "arealights-part.json", {"machine": info, **results}, indent=2)
    (args.out_dir / "arealights-part.md").write_text(markdown)
    print(markdown)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
