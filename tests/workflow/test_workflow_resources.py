"""ureterfsi.workflow.resources: the memory, out-of-core, priority and launcher decisions (no snakemake)."""
from pathlib import Path

import pytest
import yaml

from ureterfsi.workflow import resources as r

REPO = Path(__file__).resolve().parents[2]

CFG = {"study": {"memory_headroom_mb": 2000,
                 "memory_mb": {"axisymmetric": 1000, "symmetry_factor": {"quarter": 1, "half": 2, "full": 4},
                               "one_way": {"coarse": 5500, "medium": 7000},
                               "fully_coupled": {"coarse": 4000, "medium": 17000},
                               "partitioned": {"coarse": 3000, "medium": 6000}}},
       "solver": {"fully_coupled_scheme": "monolithic"},
       "mesh": {"levels": {"coarse": {"size_factor": 2.0}, "medium": {"size_factor": 1.4},
                           "fine": {"size_factor": 1.0}}}}


def test_memory_reservation_by_rung_symmetry_and_level():
    assert r.solve_mem_mb(CFG, "fully_coupled", "axisymmetric", "fine") == 1000
    assert r.solve_mem_mb(CFG, "one_way", "quarter", "medium") == 7000
    assert r.solve_mem_mb(CFG, "fully_coupled", "half", "coarse") == 8000
    assert r.solve_mem_mb(CFG, "one_way", "quarter", "fine") == 7000          # no entry: the largest
    assert r.local_memory_budget(CFG, 24000) == 22000


def test_a_fully_coupled_solve_reserves_its_schemes_entry():
    """Newton on the whole system reserves `fully_coupled`, the partitioned sweeps `partitioned`: the solve's own
    scheme where given (a design study's), else the configuration's; the one-way rung has no scheme."""
    assert r.solve_mem_mb(CFG, "fully_coupled", "quarter", "medium", "partitioned") == 6000
    assert r.solve_mem_mb(CFG, "fully_coupled", "quarter", "medium", "monolithic") == 17000
    partitioned = CFG | {"solver": {"fully_coupled_scheme": "partitioned"}}
    assert r.solve_mem_mb(partitioned, "fully_coupled", "half", "coarse") == 6000
    assert r.solve_mem_mb(partitioned, "fully_coupled", "half", "coarse", "monolithic") == 8000
    assert r.solve_mem_mb(partitioned, "one_way", "quarter", "coarse") == 5500
    assert r.out_of_core(CFG, "fully_coupled", "quarter", "medium", 16000, "partitioned") == 0
    assert r.node_refusal(CFG, "one_way", "quarter", "medium", 6500, "partitioned") != ""


def test_two_coarse_fully_coupled_design_solves_fit_side_by_side():
    """The shipped configuration: a design study's fully coupled points (partitioned sweeps, the study's overlay)
    reserve the `partitioned` entry, so that two coarse ones run together within a 24 GiB machine's budget, where
    Newton's whole-system entry would run them one at a time."""
    from ureterfsi.config import load_config_files
    from ureterfsi.designs import jobs
    from ureterfsi.designs.expand import studies

    cfg = load_config_files([REPO / "config" / "config.yaml", REPO / "config" / "designs" / "occlusion_holes.yaml"])
    st = studies(cfg)["occlusion_holes"]
    solve = jobs.point_solve(st, st.points[0].id)
    assert jobs.scheme(solve) == "partitioned" != cfg["solver"]["fully_coupled_scheme"]
    budget = r.local_memory_budget(cfg, 24 * 1024)
    assert 2 * r.solve_mem_mb(cfg, *jobs.rung(solve), jobs.scheme(solve)) <= budget
    assert 2 * r.solve_mem_mb(cfg, *jobs.rung(solve)) > budget


def test_out_of_core_only_for_a_fully_coupled_solve_over_the_budget():
    assert r.out_of_core(CFG, "fully_coupled", "quarter", "medium", 16000) == 1
    assert r.out_of_core(CFG, "fully_coupled", "quarter", "medium", 17000) == 0
    assert r.out_of_core(CFG, "fully_coupled", "quarter", "medium", None) == 0   # a cluster run: no budget
    assert r.out_of_core(CFG, "one_way", "quarter", "medium", 100) == 0


def test_finer_levels_first():
    assert [r.level_priority(CFG, lv) for lv in ("fine", "medium", "coarse")] == [2, 1, 0]


def test_longest_solves_first():
    """Finer levels first, then within a level the models with more side holes (the paper's: 22, 12, 6, none), so
    that the shortest coarse run is the one left to fill the slot beside the fine run."""
    cfg = CFG | {"models": yaml.safe_load((REPO / "config" / "config.yaml").read_text())["models"]}
    runs = [(m, lv) for lv in ("coarse", "medium", "fine") for m in ("1", "2", "3", "4")]
    ranked = sorted(runs, key=lambda ml: -r.solve_priority(cfg, *ml))
    assert ranked[:4] == [("2", "fine"), ("3", "fine"), ("4", "fine"), ("1", "fine")]
    assert ranked[-4:] == [("2", "coarse"), ("3", "coarse"), ("4", "coarse"), ("1", "coarse")]
    assert len({r.solve_priority(cfg, *ml) for ml in runs}) == len(runs)
    assert r.wall_priority(cfg) > max(r.solve_priority(cfg, *ml) for ml in runs)


@pytest.mark.parametrize("fidelity, symmetry, tasks, expected", [
    ("fully_coupled", "quarter", 4, "mpiexec -n 4 py"),
    ("fully_coupled", "quarter", 1, "py"),
    ("fully_coupled", "axisymmetric", 4, "py"),
    ("one_way", "quarter", 4, "py"),
])
def test_launcher(fidelity, symmetry, tasks, expected):
    mpi = r.mpi_resource(fidelity, symmetry)
    assert r.launcher(fidelity, symmetry, tasks, mpi or "mpiexec", python="py") == expected
    assert (mpi == "mpiexec") == (fidelity == "fully_coupled" and symmetry != "axisymmetric")


def test_the_shipped_configuration_reserves_what_its_table_says():
    from ureterfsi.config import load_config_files
    cfg = load_config_files([REPO / "config" / "config.yaml"])
    table = yaml.safe_load((REPO / "config" / "config.yaml").read_text())["study"]["memory_mb"]
    assert r.solve_mem_mb(cfg, "one_way", "quarter", "coarse") == int(table["one_way"]["coarse"])


def test_a_solve_larger_than_a_node_is_refused_unless_it_can_go_out_of_core(cfg):
    one_way = r.solve_mem_mb(cfg, "one_way", "quarter", "fine")
    assert r.node_refusal(cfg, "one_way", "quarter", "fine", None) == ""               # node size unknown
    assert r.node_refusal(cfg, "one_way", "quarter", "fine", one_way) == ""            # fits exactly
    why = r.node_refusal(cfg, "one_way", "quarter", "fine", one_way - 1)
    assert why == (f"needs {one_way} MiB (study.memory_mb), more than a node has "
                   f"(cluster.mem_mb_per_node: {one_way - 1})")
    coupled = r.solve_mem_mb(cfg, "fully_coupled", "quarter", "fine")
    assert r.node_refusal(cfg, "fully_coupled", "quarter", "fine", coupled - 1) == ""  # factors on disk instead
