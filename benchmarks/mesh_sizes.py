"""Element counts, nodes, quality and wall time of every model x level mesh (paper §2.4.1, Table 1).

    .venv/bin/python benchmarks/mesh_sizes.py [--symmetry S] [--models 1,2,3,4] [--levels coarse,...]
                                              [config.yaml [overlay.yaml ...]]

Meshes are built into a temporary directory; the table goes to stdout.
"""
import argparse
import tempfile
from pathlib import Path

from ureterfsi.config import DEFAULT_CONFIG, load_config_files
from ureterfsi.mesh.build import build_mesh


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("configs", nargs="*", default=[str(DEFAULT_CONFIG)])
    ap.add_argument("--symmetry", help="default: mesh.symmetry of the configuration")
    ap.add_argument("--models", help="comma-separated, default: all")
    ap.add_argument("--levels", help="comma-separated, default: all")
    args = ap.parse_args()
    cfg = load_config_files(args.configs)
    symmetry = args.symmetry or cfg["mesh"]["symmetry"]
    models = args.models.split(",") if args.models else sorted(cfg["models"], key=int)
    levels = args.levels.split(",") if args.levels else list(cfg["mesh"]["levels"])
    head = (f"{'model':>5} {'level':>7} {'f':>5} {'fluid':>8} {'ureter':>8} {'stent':>8} {'total':>8} "
            f"{'nodes':>8} {'minSICN':>8} {'holes':>5} {'time s':>7}")
    print(f"symmetry: {symmetry}\n{head}", flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for model in models:
            for level in levels:
                stem = Path(tmp) / f"model{model}_{level}"
                i = build_mesh(cfg, model, level, symmetry, stem.with_suffix(".msh"), stem.with_suffix(".json"))
                c = i["cells"]
                print(f"{model:>5} {level:>7} {i['size_factor']:>5.3g} {c.get('fluid', 0):>8} {c.get('ureter', 0):>8} "
                      f"{c.get('stent', 0):>8} {i['cells_total']:>8} {i['nodes']:>8} "
                      f"{i['quality_minSICN']['min']:>8.3f} {i['hole_channels_found']:>5} "
                      f"{i['mesh_wall_time_s']:>7.1f}", flush=True)


if __name__ == "__main__":
    main()
