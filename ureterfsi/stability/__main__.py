"""python -m ureterfsi.stability [--config ...] [--case NAME ...] [--end T] --out DIR: run cases."""
import argparse
import logging
from pathlib import Path

from ..config import load_config_files
from ..workflow import paths
from . import case_by_name, cases, run_case, write_case


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m ureterfsi.stability")
    ap.add_argument("--config", nargs="+", default=["config/config.yaml"])
    ap.add_argument("--case", nargs="*", default=None, help="case names (default: every case)")
    ap.add_argument("--end", type=float, default=None)
    ap.add_argument("--out", default=paths.STABILITY)
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    cfg = load_config_files(args.config)
    chosen = [case_by_name(cfg, n) for n in args.case] if args.case else cases(cfg)
    for c in chosen:
        write_case(run_case(cfg, c, end=args.end), Path(args.out) / f"{c.name}.nc")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
