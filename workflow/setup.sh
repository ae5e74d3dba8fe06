#!/usr/bin/env bash
# Idempotent set-up of ureterfsi on Debian 12: Debian's FEniCSx/gmsh/MPI stack, then a venv
# that sees it (--system-site-packages) with the pure-Python tools from pip at the versions of
# workflow/envs/lock.txt, numpy pinned to Debian's build (workflow/envs/constraints.txt); prints both
# sides' versions. A second run only checks and returns.
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

# Every pip-side distribution is pinned by workflow/envs/lock.txt (bash workflow/envs/lock.sh makes it);
# a lock older than requirements.txt/constraints.txt is refused rather than installed around.
want_req=$(cat workflow/envs/requirements.txt workflow/envs/constraints.txt | sha256sum | cut -d' ' -f1)
if ! head -1 workflow/envs/lock.txt | grep -q "requirements sha256 $want_req"; then
  echo "setup: workflow/envs/lock.txt does not match requirements.txt + constraints.txt: run bash workflow/envs/lock.sh" >&2
  exit 1
fi
stamp=.venv/.ureterfsi-requirements
want=$(cat workflow/envs/requirements.txt workflow/envs/constraints.txt workflow/envs/lock.txt | sha256sum | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "setup: installing Python packages into .venv (workflow/envs/lock.txt)"
  .venv/bin/pip install -q --disable-pip-version-check -c workflow/envs/constraints.txt \
    -c workflow/envs/lock.txt -r workflow/envs/lock.txt -r workflow/envs/requirements.txt
  echo "$want" > "$stamp"
fi
echo "setup: pip side (.venv): $(.venv/bin/pip freeze --local --disable-pip-version-check | tr '\n' ' ')"
echo "setup: Debian side: $(grep -v '^#' workflow/envs/debian.txt | cut -d= -f1 | xargs dpkg-query -W -f '${Package}=${Version} ' 2>/dev/null || true)"
while IFS= read -r pv; do
  have=$(dpkg-query -W -f '${Package}=${Version}' "${pv%%=*}" 2>/dev/null || echo "${pv%%=*} missing")
  [ "$have" = "$pv" ] || echo "setup: warning: Debian $have, workflow/envs/debian.txt says $pv" >&2
done < <(grep -v '^#' workflow/envs/debian.txt)

# The package itself (pyproject.toml), editable: its dependencies are the two sides above, so --no-deps, and it is
# built by the venv's setuptools (Debian's, a dependency of python3-pip; >= 64 for an editable install), so
# --no-build-isolation (no download).
installed=$(.venv/bin/pip show --disable-pip-version-check ureterfsi 2>/dev/null || true)
if ! grep -qx "Editable project location: $root" <<< "$installed" || [ pyproject.toml -nt .venv/.ureterfsi-editable ]; then
  echo "setup: installing ureterfsi into .venv (pip install -e .)"
  .venv/bin/pip install -q --disable-pip-version-check --no-deps --no-build-isolation -e .
  touch .venv/.ureterfsi-editable
fi

.venv/bin/python - <<'PY'
import numpy, petsc4py, dolfinx, gmsh, snakemake, xarray, ureterfsi
print(f"setup: ok (ureterfsi {ureterfsi.__version__}, dolfinx {dolfinx.__version__}, gmsh {gmsh.__version__}, numpy {numpy.__version__}, "
      f"snakemake {snakemake.__version__}, xarray {xarray.__version__})")
PY
