"""The pinned environment: workflow/envs/lock.txt covers requirements.txt, is current, and the
venv this suite runs in has exactly its versions; Debian's side is stated in workflow/envs/debian.txt."""
import hashlib
import re
from importlib import metadata

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ENVS = "workflow/envs"


def _lock(repo_root):
    text = (repo_root / ENVS / "lock.txt").read_text()
    pins = {}
    for ln in text.splitlines():
        spec = ln.split("#")[0].strip()
        if spec:
            name, version = spec.split("==")
            pins[canonicalize_name(name)] = version
    return text, pins


def test_lock_covers_every_requirement_and_is_current(repo_root):
    text, pins = _lock(repo_root)
    digest = hashlib.sha256(b"".join((repo_root / ENVS / f).read_bytes()
                                     for f in ("requirements.txt", "constraints.txt"))).hexdigest()
    assert f"requirements sha256 {digest}" in text.splitlines()[0], "lock.txt is stale: bash workflow/envs/lock.sh"
    reqs = [Requirement(ln.split("#")[0].strip()) for ln in (repo_root / ENVS / "requirements.txt").read_text()
            .splitlines() if ln.split("#")[0].strip()]
    for req in reqs:
        name = canonicalize_name(req.name)
        assert name in pins, f"{req.name} of requirements.txt is not in lock.txt"
        assert req.specifier.contains(pins[name], prereleases=True), f"lock.txt {name}=={pins[name]} breaks {req}"
    assert pins["numpy"] == "1.24.2" and pins["snakemake-executor-plugin-slurm"] == "1.4.0"


def test_installed_versions_are_the_locked_ones(repo_root):
    _, pins = _lock(repo_root)
    wrong = {name: (metadata.version(name), v) for name, v in pins.items() if metadata.version(name) != v}
    assert not wrong, f"installed != lock.txt: {wrong}; run bash workflow/setup.sh"


def test_debian_versions_are_stated(repo_root):
    lines = [ln for ln in (repo_root / ENVS / "debian.txt").read_text().splitlines() if not ln.startswith("#")]
    pkgs = dict(ln.split("=", 1) for ln in lines)
    for p in ("python3-dolfinx", "python3-gmsh", "python3-petsc4py", "python3-numpy", "libopenblas0-pthread"):
        assert re.match(r"^[\w:.+~-]+$", pkgs.get(p, "")), f"{p} has no version in debian.txt"
