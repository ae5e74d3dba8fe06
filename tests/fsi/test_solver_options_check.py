"""fsi.options.SolverOptions.check: the options' cross-checks, without a scene or a mesh."""
import pytest

from ureterfsi.fsi.options import SolverOptions


@pytest.mark.parametrize("options, scene, message", [
    ({"mesh_motion_coupling": "segregated"}, {}, "segregated mesh motion needs a fluid-alone scene"),
    ({}, {"fluid": True, "solid": False, "prescribed_motion": True}, r"Scene.mesh_motion .* needs mesh_motion_coupling"),
    ({"linear_solver": "fieldsplit"}, {}, "linear_solver 'fieldsplit' preconditions the fluid-alone"),
    ({"linear_solver": "block_gauss_seidel", "mesh_motion_coupling": "segregated"}, {"solid": False},
     "preconditions the coupled FSI system"),
    ({"mesh_jacobian_stiffening": -1.0}, {}, "mesh_jacobian_stiffening >= 0"),
    ({"mesh_jacobian_stiffening": 1.0, "coupling_scheme": "partitioned"}, {}, "mesh_jacobian_stiffening > 0"),
    ({"coupling_scheme": "partitioned"}, {"solid": False}, "coupling_scheme 'partitioned' splits a coupled scene"),
    ({"predictor": "nonsense"}, {}, "predictor .*, got .nonsense."),
])
def test_options_that_do_not_go_together_are_refused(options, scene, message):
    with pytest.raises(ValueError, match=message):
        SolverOptions(**options).check(**scene)


def test_the_defaults_and_a_fluid_alone_segregated_problem_pass():
    SolverOptions().check()
    SolverOptions(mesh_motion_coupling="segregated", linear_solver="fieldsplit").check(solid=False,
                                                                                      prescribed_motion=True)
