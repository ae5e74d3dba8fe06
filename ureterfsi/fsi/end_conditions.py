"""Open boundaries whose normal stress is a time function or a 0D (lumped) model of what lies beyond the face.

An OpenBoundary's `condition` (None: the constant `normal_stress`) is one of
  Waveform      f0 = p(t), a pressure history;
  Compartment   a compliance C filled at Q_source(t): C dp/dt = Q_source(t) + Q, f0 = p;
  Valve         a one-way resistance to a downstream pressure: f0 = p_d(t) + dp(Q), dp a smooth monotone switch
                between R_f Q (forward flow) and R_b Q (backflow);
with Q = s int_face (v - w) . n da the flux leaving the 3D domain through the face, n its outward normal and
s = `flux_scale` the whole model's flux per modelled flux (2 for a half model: the 0D model sees the whole flux).

Time discretisation: the compartment's d/dt is the 3D problem's own BDF (b0 p + b1 p_n + b2 p_n-1)/dt, so
p^{n+1} = (dt (Q_source + Q^{n+1})/C - b1 p_n - b2 p_n-1)/b0 is affine in Q^{n+1}; a steady solve (b0 = 0) drains
the source, Q = -Q_source, by STEADY_PASSES Backward Euler pseudo-steps of STEADY_PSEUDO_STEP (the pressure that
drains it is the solution, the configured one the start). The face pressure is evaluated from the current iterate
at every residual (implicit coupling). Newton's Jacobian gains the rank-k term sum_i (dp_i/dQ_i) s_i a_i c_i^T, a_i = int n da . phi,
c_i = d/dx int (v - w) . n da, applied by the Woodbury identity on the kept factorisation of the 3D Jacobian A:
    dx = y - Z (I + D C^T Z)^-1 D C^T y,  y = A^-1 b,  Z = A^-1 [a_1 .. a_k],  D = diag(s_i dp_i/dQ_i),
one extra back-substitution per boundary and factorisation (Z and C^T Z are kept with it; D, the conditions'
slopes, is the current iterate's at every iteration), so the exact Jacobian and Newton's quadratic
convergence at the cost of a few vector assemblies (Vignon-Clementel et al. 2006 couple 0D outlets implicitly).
The partitioned scheme (fsi.partitioned) applies the same update on its flow block's kept LU, a_i and c_i restricted
to the block's rows and columns.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from . import physics

# A steady state drains the compartment's source (Q = -Q_source): solved as Backward Euler pseudo-steps of this
# length from the last pressure, each leaving a fraction R C / STEADY_PSEUDO_STEP of the imbalance (R the resistance
# beyond the face; urinary compartments relax in seconds to minutes, R C < 1e2 s)
STEADY_PSEUDO_STEP = 1.0e3      # s
STEADY_PASSES = 3


@dataclass
class Waveform:
    """Normal stress f0 = pressure(t) (Pa), a float callable of time."""
    pressure: Callable[[float], float]

    def start(self):
        return self.pressure(0.0)

    def face_pressure(self, q, t, history):
        return self.pressure(t), 0.0


@dataclass
class Compartment:
    """A compliance chamber beyond the face: C dp/dt = source(t) + Q (Q leaving the 3D domain fills it).
    compliance C (m^3/Pa), source Q_source(t) (m^3/s, float callable), initial_pressure p(0) (Pa)."""
    compliance: float
    source: Callable[[float], float]
    initial_pressure: float

    def start(self):
        return self.initial_pressure

    def face_pressure(self, q, t, history):
        """(p, dp/dQ) of the BDF step with coefficients history = (b0, b1, b2, dt, p_n, p_nm1)."""
        b0, b1, b2, dt, p_n, p_nm1 = history
        if b0 == 0.0:       # steady: one Backward Euler pseudo-step of STEADY_PSEUDO_STEP from p_n
            rate = STEADY_PSEUDO_STEP / self.compliance
            return p_n + rate * (self.source(t) + q), rate
        rate = dt / (self.compliance * b0)
        return rate * (self.source(t) + q) - (b1 * p_n + b2 * p_nm1) / b0, rate


@dataclass
class Valve:
    """One-way resistance to a downstream pressure: f0 = downstream(t) + dp(Q), with
        dp(Q) = (R_f + R_b)/2 Q + (R_f - R_b)/2 (sqrt(Q^2 + Q_w^2) - Q_w),  Q_w = dp_w / (R_b - R_f),
    a hyperbola with asymptotes R_f Q (forward, Q >> Q_w) and R_b Q (backflow, Q << -Q_w), both offset by dp_w/2:
    monotone (dp/dQ between R_f and R_b) and smooth, so Newton converges. forward_resistance R_f <=
    backward_resistance R_b (Pa s/m^3), smoothing_pressure dp_w (Pa): the width of the switch in pressure."""
    downstream: Callable[[float], float]
    forward_resistance: float
    backward_resistance: float
    smoothing_pressure: float

    def start(self):
        return self.downstream(0.0)

    def pressure_drop(self, q):
        """(dp(Q), d dp/dQ)."""
        rf, rb = self.forward_resistance, self.backward_resistance
        if rb == rf:
            return rf * q, rf
        qw = self.smoothing_pressure / (rb - rf)
        root = math.hypot(q, qw)
        return 0.5 * (rf + rb) * q + 0.5 * (rf - rb) * (root - qw), 0.5 * (rf + rb) + 0.5 * (rf - rb) * q / root

    def face_pressure(self, q, t, history):
        dp, slope = self.pressure_drop(q)
        return self.downstream(t) + dp, slope


class FaceFlux:
    """The flux int (v - w) . n da leaving the 3D domain through the faces `tags` (modelled, unscaled), in the parts
    of the scene's flux_split indicator chi (int chi ..., the rest; one part without it), from the UFL integrand
    `flux` = (v - w) . J F^-T N weight with w the BDF mesh velocity of the current iterate. `recorded`: the parts
    at the last accepted state (EndConditions.accept, hold), for observers: after a step the forms' history has
    moved on to the next step's."""

    def __init__(self, pb, tags, flux, split=None):
        ds = pb.ds(tuple(tags))
        self.pb, self.total_form = pb, fem.form(flux * ds)
        self.part_form = None if split is None else fem.form(split * flux * ds)
        self.recorded = self.parts()

    def total(self) -> float:
        return self.pb.comm.allreduce(fem.assemble_scalar(self.total_form))

    def parts(self) -> list:
        """[chi part, the rest] (with a split), or [total], at the current iterate (collective)."""
        total = self.total()
        if self.part_form is None:
            return [total]
        part = self.pb.comm.allreduce(fem.assemble_scalar(self.part_form))
        return [part, total - part]

    def record(self) -> None:
        self.recorded = self.parts()


class EndConditions:
    """The open boundaries of `problem` with a `condition`: their face pressure constants (the residual's f0),
    flux forms, the Jacobian's Woodbury update and the compartments' pressure history (p_n, p_n-1)."""

    def __init__(self, problem, v, u, w, phi):
        self.pb = pb = problem
        ops = pb.ops
        F = physics.deformation_gradient(ops, u)
        n_da = ufl.det(F) * ufl.inv(F).T * ops.normal()
        self._flux = ufl.dot(ops.vec(v) - ops.vec(w), n_da) * ops.weight
        self.boundaries = [ob for ob in pb.scene.open_boundaries if ob.condition is not None]
        self.pressure = {}
        self._faces = {}              # FaceFlux by tags: the conditions' and the observers' (face_flux)
        self.a_forms, self.c_forms = [], []
        for ob in self.boundaries:
            ds = pb.ds(tuple(ob.tags))
            self.pressure[id(ob)] = fem.Constant(pb.mesh, float(ob.condition.start()))
            self.face_flux(ob.tags)
            if not isinstance(ob.condition, Waveform):      # a waveform's pressure does not depend on the state
                self.a_forms.append(fem.form(ufl.dot(n_da, ops.vec(phi)) * ops.weight * ds))
                self.c_forms.append(fem.form(ufl.derivative(self._flux * ds, pb.x)))
        self.coupled = [i for i, ob in enumerate(self.boundaries) if not isinstance(ob.condition, Waveform)]
        k = len(self.boundaries)
        self.p = np.array([float(self.pressure[id(ob)].value) for ob in self.boundaries])   # current iterate
        self.p_n, self.p_nm1 = self.p.copy(), self.p.copy()
        self.q = np.zeros(k)                 # whole-model flux Q of the current iterate
        self.slope = np.zeros(k)             # s dp/dQ at the current iterate
        # the kept factorisation's a_i, Z_i = A^-1 a_i and c_i, and C^T Z (None: no factorisation yet)
        self._a = [fem_petsc.create_vector(f) for f in self.a_forms]
        self._Z = [a.duplicate() for a in self._a]
        self._C = [fem_petsc.create_vector(f) for f in self.c_forms]
        self._CZ = None
        self._block = None          # (rows, c_i, a_i, Z_i) of a factorised diagonal block, in the block's layout
        self._used = (self._C, self._Z)     # c_i and Z_i in the layout of the kept factorisation

    def __bool__(self):
        return bool(self.boundaries)

    def normal_stress(self, ob):
        """The UFL normal stress f0 of an open boundary: its pressure constant, or its fixed value."""
        return self.pressure[id(ob)] if ob.condition is not None else ob.normal_stress

    def _history(self, i):
        pb = self.pb
        b0, b1, b2 = (float(c.value) for c in pb.bdf)
        return b0, b1, b2, float(pb.dt.value), self.p_n[i], self.p_nm1[i]

    def face_flux(self, tags) -> FaceFlux:
        """The FaceFlux of the faces `tags` (split by the scene's flux_split): one set of forms per face for the
        conditions and any observer of the face's flux (which reads its `recorded` parts after each accepted step;
        register it before the first step)."""
        key = tuple(tags)
        if key not in self._faces:
            self._faces[key] = FaceFlux(self.pb, key, self._flux, self.pb.scene.flux_split)
        return self._faces[key]

    def fluxes(self) -> np.ndarray:
        """Whole-model flux Q_i = s_i int (v - w) . n da of each boundary at the current state (collective)."""
        return np.array([ob.flux_scale * self._faces[tuple(ob.tags)].total() for ob in self.boundaries])

    def update(self) -> None:
        """Face pressures of the current iterate (called before each residual assembly)."""
        t = float(self.pb.t.value)
        self.q = self.fluxes()
        for i, ob in enumerate(self.boundaries):
            p, dpdq = ob.condition.face_pressure(self.q[i], t, self._history(i))
            self.p[i], self.slope[i] = p, ob.flux_scale * dpdq
            self.pressure[id(ob)].value = p

    @staticmethod
    def _assemble(vec, form, bcs) -> PETSc.Vec:
        with vec.localForm() as loc:
            loc.set(0.0)
        fem_petsc.assemble_vector(vec, form)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fem_petsc.set_bc(vec, bcs, None, 0.0)        # constrained rows and columns are the identity's
        return vec

    def factorised(self, solve, rows: np.ndarray | None = None) -> None:
        """After a fresh factorisation of the Jacobian A, or of its diagonal block on the owned local dofs `rows` (the
        partitioned scheme's flow block, in the block's own layout, a_i and c_i restricted to its rows and columns):
        c_i at the current iterate, Z_i = A^-1 a_i by `solve(rhs, out)` and C^T Z. They do not depend on the
        conditions' slopes: D is the current iterate's at every correction."""
        if not self.coupled:
            return
        bcs = self.pb.bcs
        for c, f in zip(self._C, self.c_forms):
            self._assemble(c, f, bcs)
        for a, f in zip(self._a, self.a_forms):
            self._assemble(a, f, bcs)
        C, rhs, Z = self._C, self._a, self._Z
        if rows is not None:
            if self._block is None or self._block[0] is not rows:
                k = len(C)
                vecs = [PETSc.Vec().createMPI((len(rows), PETSc.DECIDE), comm=self.pb.comm) for _ in range(3 * k)]
                self._block = (rows, vecs[:k], vecs[k:2 * k], vecs[2 * k:])
            _, C, rhs, Z = self._block
            for whole, part in zip(self._C + self._a, C + rhs):
                part.array[:] = whole.array_r[rows]
        for a, z in zip(rhs, Z):
            solve(a, z)
        self._used = (C, Z)
        self._CZ = np.array([[c.dot(z) for z in Z] for c in C])

    def correct(self, dx: PETSc.Vec) -> None:
        """dx <- dx - Z (I + D C^T Z)^-1 D C^T dx (Woodbury; dx = A^-1 b on entry, in the layout of the last
        `factorised`), D = diag(s_i dp_i/dQ_i) of the current iterate (update()), so the rank-k term is the current
        Jacobian's also on a kept factorisation."""
        if self._CZ is None:
            return
        C, Z = self._used
        D = np.diag(self.slope[self.coupled])
        coef = np.linalg.solve(np.eye(len(Z)) + D @ self._CZ, D @ np.array([c.dot(dx) for c in C]))
        for z, g in zip(Z, coef):
            dx.axpy(-g, z)

    def accept(self) -> None:
        """After an accepted step (before the problem's history moves on): shift the compartments' history and
        record the faces' fluxes."""
        self.p_nm1[:] = self.p_n
        self.p_n[:] = self.p
        for face in self._faces.values():
            face.record()

    @property
    def compartments(self) -> bool:
        return any(isinstance(ob.condition, Compartment) for ob in self.boundaries)

    def hold(self) -> None:
        """A steady state: the history is the current pressure; the faces' fluxes recorded."""
        self.p_nm1[:] = self.p
        self.p_n[:] = self.p
        for face in self._faces.values():
            face.record()

    def state(self) -> dict:
        return {"p": self.p.tolist(), "p_n": self.p_n.tolist(), "p_nm1": self.p_nm1.tolist()}

    def set_state(self, state: dict) -> None:
        for key in ("p", "p_n", "p_nm1"):
            getattr(self, key)[:] = state[key]
        for ob, p in zip(self.boundaries, self.p):
            self.pressure[id(ob)].value = p
