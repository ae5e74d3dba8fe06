"""Symmetry conditions are exact: the quarter model equals the full model on the mirrored quarter mesh.

The quarter and full study meshes are generated separately (their stent and hole quantities differ by
4-7 % on the 50 mm model, the ladder's one_way_full rung). `ureterfsi.mesh.io.mirror_mesh` repeats the
quarter mesh node for node across x = 0 and y = 0, so the two solves below share one discretisation and
differ only by the mirror-plane conditions, which hold exactly for the centred stent: what the quarter
model loses against the full one on its own mesh is round-off (measured 1e-13), and the ladder's 4-7 % are
mesh differences, not symmetry errors.
"""
from __future__ import annotations

import numpy as np
import pytest

from ureterfsi.study import oneway
from ureterfsi.config import load_config_files
from ureterfsi.mesh.build import build_mesh
from ureterfsi.mesh.io import mirror_mesh
from ureterfsi.study.options import RunSpec


@pytest.fixture(scope="module")
def pair(repo_root, tmp_path_factory):
    """One-way runs of the 10 mm segment, model 4 (one hole pair), quarter mesh and its mirror image."""
    tmp = tmp_path_factory.mktemp("symmetry")
    cfg = load_config_files([repo_root / "config/config.yaml", repo_root / "config/segment-10mm.yaml"])
    # the same arithmetic needs the same Newton path. At the one-way default (0.7) the paths part: the quarter took 6
    # and 8 Newton iterations (5 fresh Jacobians), the full model 6 and 15 (4), and the outlet flux differed by 3e-9
    # (Newton's absolute tests see the full model's residual norm at twice the quarter's); at 0.3 they agree (1e-13)
    cfg["solver"]["one_way_reuse_contraction"] = 0.3
    build_mesh(cfg, "4", "coarse", "quarter", tmp / "quarter.msh", tmp / "quarter.json")
    counts = mirror_mesh(tmp / "quarter.msh", tmp / "full.msh", "quarter")
    runs = {sym: oneway.run(cfg, RunSpec("4", "coarse", sym, str(tmp / f"{sym}.msh"), end=0.04),
                            str(tmp / f"{sym}.nc")) for sym in ("quarter", "full")}
    return runs, counts


def test_mirrored_mesh_is_four_quarters(pair):
    runs, counts = pair
    assert counts["cells"] == 4 * runs["quarter"].attrs["cells"] == runs["full"].attrs["cells"]


def test_quarter_model_equals_full_model_on_the_mirrored_mesh(pair):
    runs, _ = pair
    q, f = runs["quarter"], runs["full"]
    assert q.attrs["symmetry"] == "quarter" and f.attrs["symmetry"] == "full"
    for name in ("outlet_flux", "inlet_flux", "fluid_volume", "stent_max_von_mises", "stent_von_mises_line",
                 "hole_velocity_y", "wall_radial_displacement"):
        a, b = q[name].values, f[name].values
        scale = np.nanmax(np.abs(b))          # (NaN: hole-velocity points on the hole edge, in both)
        assert scale > 0 and a.shape == b.shape, name
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * scale, err_msg=name)
    # the full model has both holes of the pair; each carries what the quarter's one does
    assert list(f["hole_side"].values) == [1.0, -1.0] and list(q["hole_side"].values) == [1.0]
    hq, hf = q["hole_flux"].transpose("time", "hole").values[:, 0], f["hole_flux"].transpose("time", "hole").values
    assert np.abs(hq).max() > 0
    np.testing.assert_allclose(hf, np.c_[hq, hq], rtol=0, atol=1e-9 * np.abs(hq).max())


def test_mirror_refuses_a_full_mesh(tmp_path):
    with pytest.raises(ValueError, match="'half' or 'quarter'"):
        mirror_mesh(tmp_path / "x.msh", tmp_path / "y.msh", "full")
