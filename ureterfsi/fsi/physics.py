"""Physics blocks: small functions returning UFL residual forms on the reference configuration.

Notation (total ALE, everything pulled back to the reference mesh):
  u displacement (solid displacement in solids, ALE mesh displacement in the fluid),
  v velocity, p fluid pressure, pi solid pressure (mixed hyperelastic formulation),
  F = I + Grad u, J = det F, dvdt/dudt the BDF time derivatives at fixed reference point,
  w = dudt the mesh velocity. `ops` is an Operators instance, `dx` a (tagged) measure.
Each residual is the weak form R(...; test) = 0 (paper eqs. 1-7, 14-25).
"""
from __future__ import annotations

import ufl

from .materials import LinearElastic, MooneyRivlin, NewtonianFluid


def deformation_gradient(ops, u):
    """F = I + Grad u (paper eq. 7, 17)."""
    return ops.identity() + ops.grad(u)


def fluid_cauchy_stress(ops, fluid: NewtonianFluid, v, p, F):
    """sigma_f = -p I + mu (grad_x v + grad_x v^T), grad_x v = Grad v F^-1 (paper eqs. 2-3)."""
    grad_x_v = ops.grad(v) * ufl.inv(F)
    return -p * ops.identity() + fluid.dynamic_viscosity * (grad_x_v + grad_x_v.T)


def fluid_ale_residual(ops, fluid: NewtonianFluid, v, p, u, dvdt, w, phi, q, dx, convecting=None):
    """Incompressible Navier-Stokes in ALE form on the reference fluid domain (paper eqs. 1-3).

    int J rho (dv/dt|_X + grad_x v (c - w)) . phi + J sigma_f F^-T : Grad phi + J tr(grad_x v) q

    with the convecting velocity c = v, or a given `convecting` one (a linearly implicit step: c extrapolated from
    the previous steps makes the residual linear in v, p).
    """
    F = deformation_gradient(ops, u)
    J = ufl.det(F)
    Finv = ufl.inv(F)
    C, W, PHI = ops.vec(v if convecting is None else convecting), ops.vec(w), ops.vec(phi)
    grad_x_v = ops.grad(v) * Finv
    sigma = fluid_cauchy_stress(ops, fluid, v, p, F)
    momentum = (J * fluid.density * ufl.dot(ops.vec(dvdt) + grad_x_v * (C - W), PHI)
                + J * ufl.inner(sigma * Finv.T, ops.grad(phi)))
    continuity = J * ufl.tr(grad_x_v) * q
    return (momentum + continuity) * ops.weight * dx


def open_boundary_residual(ops, fluid: NewtonianFluid, normal_stress, backflow, v, u, w, phi, ds, convecting=None):
    """Open boundary sigma n = -f0 n (paper eq. 5) plus directional backflow stabilisation
    -beta rho/2 min((c-w).n, 0) v (energy-stable for reversed flow; beta = 0 disables), c = v or `convecting`."""
    F = deformation_gradient(ops, u)
    J = ufl.det(F)
    N = ops.normal()
    n_da = J * ufl.inv(F).T * N                     # n da = J F^-T N dA (Nanson)
    V, PHI = ops.vec(v), ops.vec(phi)
    form = normal_stress * ufl.dot(n_da, PHI)
    if backflow:
        vn = ufl.dot(ops.vec(v if convecting is None else convecting) - ops.vec(w), n_da)
        form += -backflow * 0.5 * fluid.density * 0.5 * (vn - abs(vn)) * ufl.dot(V, PHI)
    return form * ops.weight * ds


def invariants(ops, F):
    """(C, J, I1, I2) of F: C = F^T F, J = det F, I1 = tr C, I2 = (I1^2 - tr C^2)/2, the 3D invariants in plane
    strain too (C = diag(C_2D, 1): F_33 = 1, so J is unchanged; the 2D traces alone give I1b - 3 = -1 and a constant
    I2b at rest, a prestress with c01 inert)."""
    C = F.T * F
    I1 = ufl.tr(C)
    I2 = 0.5 * (I1**2 - ufl.tr(C * C))
    if ops.dim == 2:
        I1, I2 = I1 + 1.0, I2 + ufl.tr(C)
    return C, ufl.det(F), I1, I2


def mooney_rivlin_isochoric_energy(ops, mat: MooneyRivlin, F):
    """W_iso(I1b, I2b) of the five-parameter Mooney-Rivlin law (paper eq. 19, without the volumetric term),
    I1b = J^(-2/3) I1 - 3, I2b = J^(-4/3) I2 - 3."""
    _, J, I1, I2 = invariants(ops, F)
    I1b = J ** (-2.0 / 3.0) * I1 - 3.0
    I2b = J ** (-4.0 / 3.0) * I2 - 3.0
    return (mat.c10 * I1b + mat.c01 * I2b + mat.c20 * I1b**2 + mat.c02 * I2b**2 + mat.c11 * I1b * I2b)


def mooney_rivlin_first_piola(ops, mat: MooneyRivlin, u, pi):
    """P = dW_iso/dF + pi J F^-T; pi = kappa (J - 1) is the solid pressure (positive in tension).
    dW_iso/dF in closed form (I1b, I2b the shifted invariants of mooney_rivlin_isochoric_energy, W1 = dW/dI1b,
    W2 = dW/dI2b, dI1/dF = 2F, dI2/dF = 2(I1 F - F C), dJ/dF = J F^-T):
        dW_iso/dF = W1 J^(-2/3) (2F - 2/3 I1 F^-T) + W2 J^(-4/3) (2(I1 F - F C) - 4/3 I2 F^-T),
    the energy's derivative (tests/fsi/test_physics_blocks.py) at a quarter of its kernel's cost."""
    F = deformation_gradient(ops, u)
    C, J, I1, I2 = invariants(ops, F)
    F_invT = ufl.inv(F).T
    j1, j2 = J ** (-2.0 / 3.0), J ** (-4.0 / 3.0)
    I1b, I2b = j1 * I1 - 3.0, j2 * I2 - 3.0
    W1 = mat.c10 + 2.0 * mat.c20 * I1b + mat.c11 * I2b
    W2 = mat.c01 + 2.0 * mat.c02 * I2b + mat.c11 * I1b
    P_iso = (W1 * j1 * (2.0 * F - (2.0 / 3.0) * I1 * F_invT)
             + W2 * j2 * (2.0 * (I1 * F - F * C) - (4.0 / 3.0) * I2 * F_invT))
    return P_iso + pi * J * F_invT


def mooney_rivlin_residual(ops, mat: MooneyRivlin, u, pi, phi, r, dx):
    """Mixed displacement-pressure hyperelasticity: int P : Grad phi + ((J - 1) - pi/kappa) r.
    Perturbed-Lagrangian form of the volumetric energy kappa/2 (J-1)^2, free of volumetric locking
    with P2 displacement / P0 pressure."""
    J = ufl.det(deformation_gradient(ops, u))
    P = mooney_rivlin_first_piola(ops, mat, u, pi)
    return (ufl.inner(P, ops.grad(phi)) + ((J - 1.0) - pi / mat.bulk_modulus) * r) * ops.weight * dx


def elastic_first_piola(ops, mat: LinearElastic, u):
    """Hooke's law sigma = 2 mu eps + lambda tr(eps) I (paper eq. 8 without inelastic parts) for
    'linear', P = F S(E) for 'st_venant_kirchhoff'."""
    I = ops.identity()
    mu, lmbda = mat.lame_mu, mat.lame_lambda
    if mat.kinematics == "linear":
        eps = ufl.sym(ops.grad(u))
        return 2.0 * mu * eps + lmbda * ufl.tr(eps) * I
    F = deformation_gradient(ops, u)
    E = 0.5 * (F.T * F - I)                          # Green-Lagrange strain (paper eq. 11)
    return F * (2.0 * mu * E + lmbda * ufl.tr(E) * I)


def elastic_residual(ops, mat: LinearElastic, u, phi, dx):
    return ufl.inner(elastic_first_piola(ops, mat, u), ops.grad(phi)) * ops.weight * dx


def solid_inertia_residual(ops, density, dvdt, phi, dx):
    """rho_s dv/dt . phi (paper eq. 6)."""
    return density * ufl.dot(ops.vec(dvdt), ops.vec(phi)) * ops.weight * dx


def kinematic_residual(ops, dudt, v, psi, dx):
    """Solid kinematics du/dt = v; at the interface it gives the coupling u_fluid = du_solid/dt (eq. 25)."""
    return ufl.dot(ops.vec(dudt - v), ops.vec(psi)) * ops.weight * dx


def mesh_motion_residual(ops, kind, u, psi, stiffness, dx, jacobian_exponent=0.0):
    """Extension of the interface displacement into the fluid (ALE mesh motion).

    harmonic: int k Grad u : Grad psi;  elastic: int k (2 eps(u):eps(psi) + div u div psi),
    with stiffness k a cell-wise field (e.g. (V_ref/V_cell)^q) that stiffens small cells, times J^-chi,
    J = det(I + Grad u), for a `jacobian_exponent` chi > 0 (Jacobian-based stiffening, Stein, Tezduyar &
    Benney 2003: cells the motion compresses resist it more; the extension is then nonlinear in u). The weight
    is dimensionless: only the solution of these rows matters (rows at the interface are removed).
    """
    if jacobian_exponent:
        stiffness = stiffness * ufl.det(deformation_gradient(ops, u)) ** (-jacobian_exponent)
    if kind == "harmonic":
        integrand = stiffness * ufl.inner(ops.grad(u), ops.grad(psi))
    elif kind == "elastic":
        eu, ep = ufl.sym(ops.grad(u)), ufl.sym(ops.grad(psi))
        integrand = stiffness * (2.0 * ufl.inner(eu, ep) + ufl.tr(eu) * ufl.tr(ep))
    else:
        raise ValueError(f"mesh motion: 'harmonic' or 'elastic', got {kind!r}")
    return integrand * ops.weight * dx


def surface_load_residual(ops, traction, phi, ds):
    """-int t . phi dA for a traction t per reference area (paper eq. 21)."""
    return -ufl.dot(traction, ops.vec(phi)) * ops.weight * ds


def follower_pressure_traction(ops, pressure, u):
    """Traction per reference area of a pressure p on the deformed surface: P N = -p J F^-T N
    (Cauchy traction -p n, Nanson n da = J F^-T N dA); it depends on u, so its linearisation enters the
    Jacobian."""
    F = deformation_gradient(ops, u)
    return -pressure * ufl.det(F) * ufl.inv(F).T * ops.normal()


def body_force_residual(ops, force, phi, dx):
    """-int b . phi dV for a force b per reference volume (paper eq. 6 with a volume load; gravity
    b = rho_0 g)."""
    return -ufl.dot(force, ops.vec(phi)) * ops.weight * dx
