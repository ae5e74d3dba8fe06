"""Schedule and wall time of a Snakemake run (e.g. the default reproduction, `snakemake --cores 2`).

Reads a Snakemake log (default: the newest under .snakemake/log/ that executed jobs) and prints every job
with its start, end and duration, the slot (core) it ran in, the busy time of each slot, the total elapsed
time, and the chain of jobs that ended last (what the run waited for). The performance target
(the default reproduction in at most 30 min on the 2-core machine) is read off this table, never timed in a test.

    python benchmarks/reproduction.py                      # newest run
    python benchmarks/reproduction.py .snakemake/log/2026-12-02T003100.736036.snakemake.log
"""
from __future__ import annotations

import argparse
import re
from datetime import datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
STAMP = re.compile(r"^\[(\w{3} \w{3} +\d+ \d\d:\d\d:\d\d \d{4})\]$")


def parse(path: Path) -> list[dict]:
    """[{jobid, rule, output, start, end}] of the jobs a Snakemake log records (times as datetimes)."""
    jobs, stamp, current = {}, None, None
    for line in path.read_text().splitlines():
        m = STAMP.match(line.strip())
        if m:
            stamp = datetime.strptime(m.group(1), "%a %b %d %H:%M:%S %Y")
            continue
        rule = re.match(r"^(?:local)?rule (\w+):$", line.strip())
        if rule:
            current = {"rule": rule.group(1), "start": stamp, "output": "", "end": None}
            continue
        if current is not None and line.startswith("    output: "):
            current["output"] = line.split(": ", 1)[1].split(", ")[0]
        elif current is not None and line.startswith("    jobid: "):
            jobs[int(line.split(": ", 1)[1])] = current
            current = None
        done = re.match(r"^Finished jobid: (\d+)", line.strip())
        if done and int(done.group(1)) in jobs:
            jobs[int(done.group(1))]["end"] = stamp
    return [dict(jobid=k, **v) for k, v in sorted(jobs.items(), key=lambda kv: kv[1]["start"]) if v["end"]]


def assign_slots(jobs: list[dict], cores: int) -> None:
    """Give each job the first slot free at its start (jobs use one core each here)."""
    free_at = [None] * cores
    for job in jobs:
        slot = next((i for i, t in enumerate(free_at) if t is None or t <= job["start"]), None)
        if slot is None:                 # more jobs than slots at once (a multi-core job elsewhere): new slot
            free_at.append(None)
            slot = len(free_at) - 1
        job["slot"] = slot
        free_at[slot] = job["end"]


def newest_log() -> Path:
    logs = sorted((ROOT / ".snakemake" / "log").glob("*.snakemake.log"))
    for path in reversed(logs):
        if "Finished jobid" in path.read_text():
            return path
    raise SystemExit("no Snakemake log with finished jobs under .snakemake/log/")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("log", nargs="?", type=Path, default=None)
    ap.add_argument("--cores", type=int, default=2)
    args = ap.parse_args()
    path = args.log or newest_log()
    jobs = parse(path)
    if not jobs:
        raise SystemExit(f"{path}: no finished jobs")
    assign_slots(jobs, args.cores)
    t0 = min(j["start"] for j in jobs)
    t1 = max(j["end"] for j in jobs)
    print(f"{path.name}: {len(jobs)} jobs")
    print(f"{'start s':>8s} {'end s':>7s} {'dur s':>6s} slot  rule                     output")
    for j in jobs:
        print(f"{(j['start'] - t0).total_seconds():8.0f} {(j['end'] - t0).total_seconds():7.0f} "
              f"{(j['end'] - j['start']).total_seconds():6.0f} {j['slot']:4d}  {j['rule']:24s} {j['output']}")
    for s in sorted({j["slot"] for j in jobs}):
        busy = sum((j["end"] - j["start"]).total_seconds() for j in jobs if j["slot"] == s)
        print(f"slot {s}: busy {busy:.0f} s")
    work = sum((j["end"] - j["start"]).total_seconds() for j in jobs)
    elapsed = (t1 - t0).total_seconds()
    print(f"total: {elapsed:.0f} s = {elapsed / 60:.1f} min elapsed, {work:.0f} s of job time "
          f"({work / elapsed:.2f} jobs running on average)")
    # what the end waited for: from the last job back through the job that ended last before each start
    chain, cur = [], max(jobs, key=lambda j: j["end"])
    while cur is not None:
        chain.append(cur)
        before = [j for j in jobs if j["end"] <= cur["start"]]
        cur = max(before, key=lambda j: j["end"]) if before else None
    print("last-ending chain: " + " <- ".join(f"{j['rule']}({Path(j['output']).stem or '-'}, "
                                               f"{(j['end'] - j['start']).total_seconds():.0f} s)" for j in chain))


if __name__ == "__main__":
    main()
