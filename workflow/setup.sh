#!/usr/bin/env bash
# Idempotent set-up of ureterfsi on Debian 12: Debian's FEniCSx/gmsh/MPI stack, then a venv
# that sees it (--system-site-packages) with the pure-Python tools from pip, numpy pinned to
# Debian's build (workflow/envs/constraints.txt). A second run only checks and returns.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

# libopenblas0-pthread: MUMPS factorisations otherwise run on the reference BLAS (5-10x slower)
# libudunits2-0: the units library of cfchecks (CF checker of the tests)
debs=(python3-dolfinx python3-gmsh python3-venv python3-pip mpi-default-bin libopenblas0-pthread libudunits2-0)
missing=()
for p in "${debs[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo=sudo
  echo "setup: installing Debian packages: ${missing[*]}"
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv from /usr/bin/python3 (--system-site-packages)"
  /usr/bin/python3 -m venv --system-site-packages .venv
fi

stamp=.venv/.ureterfsi-requirements
want=$(cat workflow/envs/requirements.txt workflow/envs/constraints.txt | sha256sum | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "setup: installing Python packages into .venv"
  .venv/bin/pip install -q --disable-pip-version-check \
    -c workflow/envs/constraints.txt -r workflow/envs/requirements.txt
  echo "$want" > "$stamp"
fi

# Make the package importable from the venv without a build step.
site=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
echo "$root" > "$site/ureterfsi-src.pth"

.venv/bin/python - <<'PY'
import numpy, petsc4py, dolfinx, gmsh, snakemake, xarray
print(f"setup: ok (dolfinx {dolfinx.__version__}, gmsh {gmsh.__version__}, numpy {numpy.__version__}, "
      f"snakemake {snakemake.__version__}, xarray {xarray.__version__})")
PY
