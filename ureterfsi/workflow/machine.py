"""What the machine running the workflow has: its physical memory (the local memory budget of workflow/rules/common.smk)."""
from __future__ import annotations


def physical_memory_mib(meminfo: str = "/proc/meminfo") -> int:
    """MemTotal of `meminfo` (Linux), MiB."""
    with open(meminfo) as fh:
        for line in fh:
            if line.startswith("MemTotal:"):
                return int(line.split()[1]) // 1024
    raise ValueError(f"{meminfo}: no MemTotal line")
