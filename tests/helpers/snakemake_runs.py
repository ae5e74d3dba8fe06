"""Snakemake on the repository's Snakefile from the tests: the end-to-end configuration (config/config.yaml +
config/segment-10mm.yaml + tests/overlays/e2e.yaml, merged as the e2e run merges them), a run in a working
directory, and what its output says (job counts, planned jobs)."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import yaml

from ureterfsi.config import deep_merge, load_config

REPO = Path(__file__).resolve().parents[2]
CONFIGS = [REPO / "config" / "config.yaml", REPO / "config" / "segment-10mm.yaml",
           REPO / "tests" / "overlays" / "e2e.yaml"]
REPLACED = (("models",), ("mesh", "levels"), ("ladder", "rungs"))      # e2e.yaml mappings that replace instead of merge
PROFILE = REPO / "workflow" / "profiles" / "default"
SLURM_PROFILE = REPO / "workflow" / "profiles" / "slurm"


def e2e_config(path: Path, **figures) -> dict:
    """Write the merged e2e configuration to `path` (figures.* overridden by `figures`); return it."""
    layers = [yaml.safe_load(p.read_text()) for p in CONFIGS]
    cfg = layers[0]
    for layer in layers[1:]:
        cfg = deep_merge(cfg, layer)
    for keys in REPLACED:
        src, dst = layers[-1], cfg
        for k in keys[:-1]:
            src, dst = src[k], dst[k]
        dst[keys[-1]] = src[keys[-1]]
    cfg["figures"].update(figures)
    load_config(cfg)   # validates (a copy)
    path.write_text(yaml.safe_dump(cfg, sort_keys=False))
    return cfg


def snakemake(workdir: Path, config: Path, *args, profile: Path | None = PROFILE, timeout=900, **popen):
    """python -m snakemake on the repository's Snakefile in `workdir` with the e2e configuration."""
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
           "--configfile", str(config)]
    if profile is not None:
        cmd += ["--workflow-profile", str(profile)]
    cmd += [str(a) for a in args]
    if popen:
        return subprocess.Popen(cmd, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                **popen)
    return subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=timeout)


def job_counts(text: str) -> dict[str, int]:
    """{rule: count} from the 'Job stats' table of a Snakemake (dry) run."""
    out, table = {}, False
    for line in text.splitlines():
        if line.startswith("job ") and "count" in line:
            table = True
            continue
        if table:
            m = re.fullmatch(r"(\S+)\s+(\d+)", line.strip())
            if m and m.group(1) != "total":
                out[m.group(1)] = int(m.group(2))
            elif line.strip().startswith("total"):
                break
    return out


def ok(run) -> str:
    assert run.returncode == 0, (run.stdout[-3000:] + "\n" + run.stderr[-3000:])
    return run.stdout + run.stderr


def planned_jobs(text: str) -> list[dict]:
    """The jobs of a dry run (-n -p): rule, output, resources {name: value} and the shell command."""
    jobs = []
    for block in re.split(r"^(?:local)?rule ", text, flags=re.M)[1:]:
        rule, _, rest = block.partition(":\n")
        fields = dict(line.strip().split(": ", 1) for line in rest.splitlines()
                      if line.startswith("    ") and ": " in line)
        shell = re.search(r"^Shell command: (.*)$", rest, re.M)
        jobs.append({"rule": rule, "output": fields.get("output", ""), "shell": shell.group(1) if shell else None,
                     "resources": dict(kv.split("=", 1) for kv in fields.get("resources", "").split(", ") if kv)})
    return jobs
