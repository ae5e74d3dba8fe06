"""CF 1.8 compliance of a netCDF file by IOOS compliance-checker (--test=cf:1.8), for the tests of every dataset
kind."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

CHECKER = Path(sys.executable).with_name("compliance-checker")


def cf_errors(path) -> tuple[int, int]:
    """(errors, warnings) of compliance-checker --test=cf:1.8: high-priority results count as errors,
    medium-priority ones as warnings (the report at `path`.cc.json)."""
    out = Path(str(path) + ".cc.json")
    subprocess.run([str(CHECKER), "--test=cf:1.8", "-f", "json", "-o", str(out), str(path)],
                   capture_output=True, text=True, timeout=300)
    res = json.loads(out.read_text())["cf:1.8"]
    return int(res["high_count"]), int(res["medium_count"])
