"""linear_solver "block_gauss_seidel" (ureterfsi.fsi.linear_solvers): GMRES with a solid -> mesh -> flow block
Gauss-Seidel preconditioner on the coupled Newton system gives the whole-system LU's Newton iterates and
solution, on the axisymmetric Mooney-Rivlin tube (u-p mixed wall) and on Turek-Hron FSI1 (St Venant-Kirchhoff
flag); the splits are the documented ones, a wrong split does not converge; kept factors follow the policy.
"""
from __future__ import annotations

import re

import numpy as np
import pytest
from dolfinx import fem
from petsc4py import PETSc

from helpers.engine_cases import FLUID, WALL, tube_problem
from ureterfsi.fsi import BlockGaussSeidel, NewtonDivergence, SolverOptions

TIGHT = dict(newton_rtol=1e-10, newton_atol=1e-14, reuse_jacobian=True, reuse_contraction=0.3)


def _run(linear_solver, steps=4, dt=2e-3, **options):
    pb, _ = tube_problem(options=SolverOptions(linear_solver=linear_solver, **(TIGHT | options)))
    histories = [pb.solve_steady()[1]]
    for _ in range(steps):
        histories.append(pb.step(dt)[1])
    return pb, histories


@pytest.fixture(scope="module")
def lu_run():
    pb, histories = _run("mumps")
    with pb:
        yield pb, histories


def test_same_newton_iterates_and_solution_as_the_whole_system_lu(lu_run):
    lu, lu_hist = lu_run
    pb, hist = _run("block_gauss_seidel", krylov_rtol=1e-12)
    # the same residual after every Newton iteration of every step, to 1e-6 relative plus the linear solves'
    # round-off (1e-11 of the step's first residual)
    assert [len(h) for h in hist] == [len(h) for h in lu_hist]
    for h, g in zip(hist, lu_hist):
        h, g = np.array(h), np.array(g)
        big = g > 1e-7 * g[0]
        np.testing.assert_allclose(h[big], g[big], rtol=1e-6, atol=1e-11 * g[0])
    ref = lu.x.x.array
    assert np.abs(pb.x.x.array - ref).max() <= 1e-8 * np.abs(ref).max()
    c = pb.counters
    assert c["krylov_iterations"] > 0 and c["factorisations"] == lu.counters["factorisations"]
    assert pb.ksp.getPC().getType() == "fieldsplit" and pb.ksp.getType() == "gmres"


def test_inexact_newton_reaches_the_same_solution_with_fewer_krylov_iterations():
    """krylov_forcing "eisenstat_walker": each linear solve only as accurate as Newton's progress needs. At the
    configuration's Newton tolerances every field of the converged state is the LU path's to 1e-6 of its max
    norm (the velocity is the sensitive one: a forcing term up to 0.1 left it 3.6e-6 off)."""
    newton = dict(newton_rtol=1e-8, newton_atol=1e-10)
    lu, _ = _run("mumps", **newton)
    fixed, _ = _run("block_gauss_seidel", krylov_rtol=1e-10, **newton)
    pb, _ = _run("block_gauss_seidel", krylov_rtol=1e-10, krylov_forcing="eisenstat_walker", **newton)
    for f in pb.field_names:
        dofs = np.asarray(pb.sub(f).collapse()[1])
        ref = lu.x.x.array[dofs]
        assert np.abs(pb.x.x.array[dofs] - ref).max() <= 1e-6 * np.abs(ref).max(), f
    assert pb.counters["krylov_iterations"] < 0.7 * fixed.counters["krylov_iterations"], \
        (pb.counters, fixed.counters)


def test_coupling_sparsity_is_the_mixed_element_jacobian(lu_run):
    """jacobian_sparsity "couplings" (the default) stores fewer entries than the mixed element's pattern, and
    holds the same Jacobian: the same Newton history (to MUMPS's round-off on another ordering) and the same
    matrix action on random vectors."""
    lu, lu_hist = lu_run
    mixed, hist = _run("mumps", jacobian_sparsity="mixed_element")
    assert [len(h) for h in hist] == [len(h) for h in lu_hist]
    for h, g in zip(hist, lu_hist):
        np.testing.assert_allclose(h, g, rtol=0.0, atol=1e-12 * g[0])
    assert np.abs(mixed.x.x.array - lu.x.x.array).max() <= 1e-12 * np.abs(lu.x.x.array).max()
    nnz = {n: pb.A.getInfo()["nz_used"] for n, pb in (("own", lu), ("mixed", mixed))}
    assert nnz["own"] < 0.8 * nnz["mixed"], nnz
    rng = np.random.default_rng(3)
    for _ in range(3):
        r = lu.A.createVecRight()
        r.array[:] = rng.standard_normal(r.getLocalSize())
        y, z = lu.A.createVecLeft(), lu.A.createVecLeft()
        lu.A.mult(r, y)
        mixed.A.mult(r, z)
        assert (y - z).norm() <= 1e-12 * y.norm()


def test_kept_block_factors_follow_the_policy():
    """Never exceeded: solid and mesh factorised once, flow at every fresh Jacobian; always exceeded: every
    block refactorised at every fresh Jacobian after the first solve."""
    pb, _ = _run("block_gauss_seidel", steps=3, krylov_refactorise_iterations=10**6)
    c = pb.counters
    assert c["factorisations"] >= 2
    assert (c["solid_factorisations"], c["mesh_factorisations"]) == (1, 1)
    assert c["flow_factorisations"] == c["factorisations"]
    pb, _ = _run("block_gauss_seidel", steps=3, krylov_refactorise_iterations=0)
    c = pb.counters
    assert c["solid_factorisations"] == c["mesh_factorisations"] == c["flow_factorisations"] == c["factorisations"]


def _owned(pb, local):
    nloc = pb.W.dofmap.index_map.size_local * pb.W.dofmap.index_map_bs
    return np.unique(np.asarray(local)[np.asarray(local) < nloc])


def test_splits_are_the_scene_regions(lu_run):
    pb = lu_run[0]
    s = pb.layout.coupled_splits(pb.cells(pb.solid_tags), pb.constraints.pins, pb.constraints.dirichlet)
    nloc = pb.W.dofmap.index_map.size_local * pb.W.dofmap.index_map_bs
    allof = np.concatenate(list(s.values()))
    assert allof.size == nloc and np.array_equal(np.sort(allof), np.arange(nloc)), "a partition of the dofs"
    tdim = pb.mesh.topology.dim
    ct = pb.scene.cell_tags
    dofs = {f: _owned(pb, pb.W.sub(pb.index[f]).collapse()[1]) for f in pb.field_names}
    on = {f: {r: _owned(pb, fem.locate_dofs_topological(pb.W.sub(pb.index[f]), tdim, ct.find(tag)))
              for r, tag in (("fluid", FLUID), ("wall", WALL))} for f in ("velocity", "displacement")}
    for f in ("velocity", "displacement"):
        assert np.isin(on[f]["wall"], s["solid"]).all(), f"{f} of solid cells (interface included) in S"
    assert np.isin(dofs["solid_pressure"], s["solid"]).all()
    assert np.isin(s["mesh"], dofs["displacement"]).all()
    assert np.isin(s["flow"], np.union1d(dofs["velocity"], dofs["pressure"])).all()
    fluid_only = np.setdiff1d(on["displacement"]["fluid"], on["displacement"]["wall"])
    assert 0 < s["mesh"].size < fluid_only.size     # the open ends' fixed mesh rows are in S
    pinned = np.setdiff1d(dofs["pressure"], np.concatenate([s["flow"]]))
    assert pinned.size > 0 and np.isin(pinned, s["solid"]).all()


def _is(pb, dofs):
    offset = pb.W.dofmap.index_map.local_range[0] * pb.W.dofmap.index_map_bs
    return PETSc.IS().createGeneral((np.asarray(dofs) + offset).astype(PETSc.IntType), comm=pb.comm)


def test_a_wrong_split_does_not_converge(lu_run):
    """On the last Jacobian of the LU run, the interface velocity moved from S to F: GMRES stalls (the right split: a few iterations, the LU's
    solution)."""
    pb = lu_run[0]
    s = pb.layout.coupled_splits(pb.cells(pb.solid_tags), pb.constraints.pins, pb.constraints.dirichlet)
    tdim, ct = pb.mesh.topology.dim, pb.scene.cell_tags
    V = pb.W.sub(pb.index["velocity"])
    interface = np.intersect1d(_owned(pb, fem.locate_dofs_topological(V, tdim, ct.find(FLUID))),
                               _owned(pb, fem.locate_dofs_topological(V, tdim, ct.find(WALL))))
    wrong = {"solid": np.setdiff1d(s["solid"], interface), "mesh": s["mesh"], "flow": np.union1d(s["flow"], interface)}
    b = pb.A.createVecLeft()
    pb.A.mult(pb.x.vector, b)          # a right-hand side with the scales of the physics
    exact = b.duplicate()
    lu = PETSc.KSP().create(pb.comm)
    lu.setOperators(pb.A)
    lu.setType("preonly")
    lu.getPC().setType("lu")
    lu.getPC().setFactorSolverType("mumps")
    lu.solve(b, exact)
    result = {}
    for name, split in (("right", s), ("wrong", wrong)):
        ksp = PETSc.KSP().create(pb.comm)
        prefix = f"test_split_{name}_"
        ksp.setOptionsPrefix(prefix)
        ksp.setOperators(pb.A)
        bgs = BlockGaussSeidel(ksp, prefix, {n: _is(pb, d) for n, d in split.items()}, 1e-8, 100, 10, {}, {})
        ksp.setFromOptions()
        x = b.duplicate()
        bgs.solve(b, x, 1e-8)
        result[name] = (ksp.getConvergedReason(), ksp.getIterationNumber(), (x - exact).norm() / exact.norm())
    reason, its, err = result["right"]
    assert reason > 0 and its <= 10 and err <= 1e-6, result
    assert result["wrong"][0] < 0, result


def test_mumps_workspace_reaches_every_factorisation(lu_run):
    """SolverOptions.mumps_workspace_percent is ICNTL(14) of every MUMPS factor the strategies create, read back
    from the factors: the whole system, each block_gauss_seidel split, and the flow block and mesh-motion LU of a
    segregated fluid-alone solve; the default leaves MUMPS's own 20 %."""
    from helpers.fluid_tube import run as fluid_run
    assert lu_run[0].factor_matrix().getMumpsIcntl(14) == 20
    whole, _ = _run("mumps", steps=1, mumps_workspace_percent=73)
    assert whole.factor_matrix().getMumpsIcntl(14) == 73
    blocks, _ = _run("block_gauss_seidel", steps=1, mumps_workspace_percent=73)
    factors = {n: sub.getPC().getFactorMatrix() for n, sub in blocks.linear_solver.sub_ksps().items()}
    assert {n: f.getMumpsIcntl(14) for n, f in factors.items()} == {"solid": 73, "mesh": 73, "flow": 73}
    _, _, fluid = fluid_run(2e-3, 1, "segregated", mumps_workspace_percent=73)
    assert fluid.mesh_motion_solver == "lu"
    assert fluid.factor_matrix().getMumpsIcntl(14) == 73
    assert fluid.mesh_motion.ksp.getPC().getFactorMatrix().getMumpsIcntl(14) == 73


OUT_OF_CORE_SCRIPT = """
import os, sys
from mpi4py import MPI
from petsc4py import PETSc
from ureterfsi.fsi.condensation import direct
from ureterfsi.fsi.linear_solvers import Mumps, out_of_core_directory
n = 4000
A = PETSc.Mat().createAIJ((n, n), nnz=3, comm=MPI.COMM_SELF)
for i in range(n):
    A.setValues(i, [j for j in (i - 1, i, i + 1) if 0 <= j < n], [-1.0, 2.5, -1.0][(i == 0):3 - (i == n - 1)])
A.assemble()
ksp = direct(MPI.COMM_SELF, "ooc_", "lu", Mumps(out_of_core=True))
ksp.setOperators(A)
b, x = A.createVecs()
b.set(1.0)
ksp.solve(b, x)
r = b.duplicate()
A.mult(x, r)
r.axpy(-1.0, b)
print(out_of_core_directory(), len(os.listdir(out_of_core_directory())), r.norm() / b.norm(),
      ksp.getPC().getFactorMatrix().getMumpsIcntl(22))
"""


@pytest.mark.parametrize("ending", ["exit", "kill"])
def test_out_of_core_factors_go_to_a_scratch_directory_removed_with_the_process(tmp_path, ending):
    """Mumps(out_of_core=True): the factor is written to a directory of the process's own under $MUMPS_OOC_TMPDIR
    (node-local scratch on a cluster) and solves from it; the directory goes once the process has ended, by an
    exit or by SIGKILL (MUMPS deletes a factor's files only when the factor is destroyed)."""
    import os
    import subprocess
    import sys
    import time
    script = OUT_OF_CORE_SCRIPT + ("import signal; os.kill(os.getpid(), signal.SIGKILL)" if ending == "kill" else "")
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300,
                         env=os.environ | {"MUMPS_OOC_TMPDIR": str(tmp_path)})
    assert run.returncode == (-9 if ending == "kill" else 0), run.stderr[-2000:]
    directory, files, residual, icntl22 = run.stdout.split()
    assert os.path.dirname(directory) == str(tmp_path) and int(files) >= 1
    assert float(residual) < 1e-12 and int(icntl22) == 1
    for _ in range(100):
        if not os.listdir(tmp_path):
            break
        time.sleep(0.1)
    assert not os.listdir(tmp_path), os.listdir(tmp_path)
    assert "error" not in run.stderr.lower(), run.stderr[-2000:]


def test_turek_hron_fsi1_quantities_equal_the_lu_path():
    th = pytest.importorskip("ureterfsi.scenes.turek_hron")
    lu = th.run_fsi1(0.5, options=SolverOptions(linear_solver="mumps"))
    bgs = th.run_fsi1(0.5, options=SolverOptions(linear_solver="block_gauss_seidel", krylov_rtol=1e-10))
    for key in ("drag", "lift", "ux_A", "uy_A"):
        assert abs(getattr(bgs, key) - getattr(lu, key)) <= 1e-8 * abs(getattr(lu, key)), key
    assert bgs.newton_iterations == lu.newton_iterations


def test_the_fully_coupled_rung_reads_its_own_linear_solver():
    from pathlib import Path

    from ureterfsi.config import load_config_files
    from ureterfsi.study.options import solver_options
    cfg = load_config_files([str(Path(__file__).resolve().parents[2] / "config/config.yaml")])
    cfg["solver"] |= {"linear_solver": "mumps", "fully_coupled_linear_solver": "block_gauss_seidel",
                      "krylov_forcing": "eisenstat_walker"}
    coupled, other = solver_options(cfg, fully_coupled=True), solver_options(cfg)
    assert (coupled.linear_solver, other.linear_solver) == ("block_gauss_seidel", "mumps")
    assert coupled.krylov_forcing == "eisenstat_walker"
    assert coupled.coupled_solution() == "Newton + block_gauss_seidel"
    cfg["solver"] |= {"fully_coupled_scheme": "partitioned", "sweep_convergence": "contraction"}
    assert solver_options(cfg, fully_coupled=True).coupled_solution() == (
        "partitioned sweeps wall -> mesh -> urine of the monolithic residual (condensed wall LU, Anderson depth 5, "
        "contraction stop)")


def test_refusals_and_failure_report():
    from helpers.fluid_tube import tube as fluid_tube
    from ureterfsi.fsi import FluidRegion, MonolithicFSI, NewtonianFluid, Scene
    msh, ct, ft = fluid_tube(4)
    fluid_alone = Scene(msh, ct, ft, fluid=FluidRegion([1], NewtonianFluid(1000.0, 1e-3)))
    with pytest.raises(ValueError, match="needs non-empty splits"):
        MonolithicFSI(fluid_alone, SolverOptions(linear_solver="block_gauss_seidel"))
    for key in ("krylov_forcing", "jacobian_sparsity"):
        with pytest.raises(ValueError, match=f"{key} '"):
            MonolithicFSI(fluid_alone, SolverOptions(**{key: "exact"}))
    with pytest.raises(ValueError, match="mesh_motion_coupling 'monolithic'"):
        MonolithicFSI(fluid_alone, SolverOptions(linear_solver="block_gauss_seidel",
                                                 mesh_motion_coupling="segregated"))
    pb, _ = tube_problem(options=SolverOptions(linear_solver="block_gauss_seidel", krylov_max_iterations=1,
                                               krylov_rtol=1e-14))
    pb.solve_steady()               # the rest state: no linear solve
    with pytest.raises(NewtonDivergence, match="after 1 GMRES iterations"):
        pb.step(2e-3)


def test_solver_options_go_with_their_problem():
    """PETSc's options database holds at most 512 entries per process (a suite or a stability matrix poses
    hundreds of problems in one): each problem's options live under its prefix and are removed with it."""
    import gc

    from ureterfsi.scenes import verification as V
    from ureterfsi.fsi import MonolithicFSI
    gc.collect()
    base = set(PETSc.Options().getAll())
    pb = MonolithicFSI(V.channel_scene(), SolverOptions(linear_solver="block_gauss_seidel"))
    prefix = pb.options_prefix
    assert len([k for k in PETSc.Options().getAll() if k.startswith(prefix)]) > 10
    del pb
    gc.collect()
    assert not [k for k in PETSc.Options().getAll() if k.startswith(prefix)]
    assert set(PETSc.Options().getAll()) <= base


def test_a_full_options_table_is_freed_of_dead_problems_or_named():
    """Problems left in reference cycles keep their options until the cyclic collector runs; a new solver that does
    not fit in PETSc's fixed table collects them first (the suite's partitioned tests once ran out of the 512 entries
    within one module), and where live solvers fill it, the error names the table and what holds it."""
    import gc
    import weakref

    from ureterfsi.fsi.linear_solvers import OPTIONS_TABLE_SIZE, forget_options, set_options

    class Holder:
        pass

    gc.collect()
    gc.disable()                    # only set_options's own collection may free the dead holder
    try:
        dead = Holder()
        dead.cycle = dead
        room = OPTIONS_TABLE_SIZE - len(PETSc.Options().getAll())
        set_options("ureterfsi_1_", {f"k{i}": i for i in range(room - 2)})
        weakref.finalize(dead, forget_options, "ureterfsi_1_")
        del dead
        set_options("ureterfsi_2_", {f"k{i}": i for i in range(5)})
        assert not [k for k in PETSc.Options().getAll() if k.startswith("ureterfsi_1_")]
        room = OPTIONS_TABLE_SIZE - len(PETSc.Options().getAll())
        set_options("ureterfsi_3_", {f"k{i}": i for i in range(room)})
        with pytest.raises(RuntimeError, match=r"options table is full \(512 of 512 entries, \d+ live problems") as err:
            set_options("ureterfsi_4_", {"ksp_type": "preonly"})
        live = int(re.search(r"entries, (\d+) live", str(err.value)).group(1))
        assert live >= 2            # this test's two live owners, 2 and 3, and any module fixture's problem
        assert not [k for k in PETSc.Options().getAll() if k.startswith("ureterfsi_4_")]
    finally:
        gc.enable()
        for prefix in ("ureterfsi_1_", "ureterfsi_2_", "ureterfsi_3_"):
            forget_options(prefix)
