"""The partitioned sweeps' policy (fsi.partitioned): when a block's kept LU is refreshed (stale_factor,
RefreshSchedule), how the sweeps are mixed (Anderson's mixing with the differences of earlier steps, IQN-ILS with
reuse) and when a step's sweeps stop (the contraction's error bound or Newton's residual test; the accepted state's
check)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

from .newton import NewtonDivergence, fields_off


def stale_factor(norm: float, previous: float | None, options) -> bool:
    """A block's LU is stale when its update reduced the block's residual (`previous` -> `norm`) by less than
    block_reuse_contraction; a residual within newton_atol is round-off, whose ratio says nothing of the LU (on the
    50 mm ureter such ratios, ~5e-14 -> ~4e-14, refactorised the urine's LU every other step)."""
    return previous is not None and norm > max(options.block_reuse_contraction * previous, options.newton_atol)


@dataclass
class RefreshSchedule:
    """Rent or buy for the blocks' kept LUs (SolverOptions.block_refresh_sweeps = `limit`, 0: off): a stale LU
    costs sweeps, a refresh its Jacobian and factorisation. Every converged step adds its sweeps beyond the floor,
    the fewest a step needs with fresh LUs; once the sum since the wall's last refresh reaches `limit` the wall's LU
    is due, and the urine's too when no step since then came down to the floor (the urine's LU costs the sweeps)."""
    limit: int
    floor: int | None = None        # the fewest sweeps of a step with fresh LUs
    fewest: int | None = None       # the fewest sweeps of a step since the wall's last refresh
    extra: int = 0                  # sweeps beyond the floor, summed over those steps
    both_fresh: bool = False        # both LUs are due: the next step's sweeps are the new floor

    def reset(self) -> None:
        """Forget everything (the LUs are refactorised at their next use)."""
        self.floor, self.fewest, self.extra, self.both_fresh = None, None, 0, False

    def wall_refreshed(self) -> None:
        self.fewest, self.extra = None, 0

    def converged(self, sweeps: int) -> tuple[str, ...]:
        """Record a converged step's sweeps; returns the blocks whose LUs are due ("solid", maybe "flow")."""
        if not self.limit:
            return ()
        if self.floor is None or self.both_fresh:
            self.floor, self.both_fresh = sweeps, False
        self.floor = min(self.floor, sweeps)
        self.fewest = sweeps if self.fewest is None else min(self.fewest, sweeps)
        self.extra += sweeps - self.floor
        if self.extra < self.limit:
            return ()
        if self.fewest > self.floor:
            self.both_fresh = True
            return "solid", "flow"
        return ("solid",)


class SweepPolicyMethods:
    """PartitionedCoupling's mixing and stopping of the sweeps (mixed into PartitionedCoupling: they use its problem
    `pb`, its field scales `_scales()`, the differences `kept`, the contraction estimate `contraction` and the last
    sweep's `field_increments`)."""

    def _weights(self) -> np.ndarray:
        """Per owned dof 1 / max(||x_f||_inf, newton_increment_floor / newton_field_rtol) of its field, at the current
        state: the units relative to each field of Anderson's least squares and of the error bound (a field at rest,
        whose values are round-off, weighed as a 1e-4 SI one, not amplified)."""
        pb, o = self.pb, self.pb.options
        least = o.newton_increment_floor / (o.newton_field_rtol or o.newton_stol)
        w = np.zeros(pb.x.vector.getLocalSize())
        for f, s in self._scales().items():
            w[pb.layout.field_owned[f]] = 1.0 / max(s, least)
        return w

    def _anderson(self, xs: list, gs: list, w: np.ndarray) -> np.ndarray:
        """Anderson mixing (Walker & Ni 2011, type II; IQN-ILS of Degroote et al. 2009 on the whole state) of the
        fixed point x = G(x) from the owned parts of the last iterates x_i and G(x_i), and the differences kept from
        earlier steps (`self.kept`, IQN-ILS with reuse, Degroote & Vierendeels 2011):
        x+ = G(x_k) - sum_i gamma_i dG_i, gamma = argmin ||f_k - sum_i gamma_i dF_i||_w, f = G(x) - x,
        dF_i, dG_i the differences of f and G between successive iterates, the norm weighted by w (one Gram matrix
        reduced over the ranks)."""
        dX = [b - a for a, b in zip(xs[:-1], xs[1:])] + [d for d, _ in self.kept]
        dG = np.array([b - a for a, b in zip(gs[:-1], gs[1:])] + [g for _, g in self.kept])
        dF = (dG - np.array(dX)) * w
        f = (gs[-1] - xs[-1]) * w
        local = np.concatenate([(dF @ dF.T).ravel(), dF @ f])
        total = np.empty_like(local)
        self.pb.comm.Allreduce(local, total, op=MPI.SUM)
        m = len(dF)
        gram, rhs = total[:m * m].reshape(m, m), total[m * m:]
        gamma = np.linalg.lstsq(gram + 1e-14 * np.trace(gram) * np.eye(m), rhs, rcond=None)[0]
        return gs[-1] - dG.T @ gamma

    def _keep(self, xs: list, gs: list) -> None:
        """Keep the differences of this step's sweeps, newest first, with the earlier ones: the last
        anderson_depth x anderson_reuse of them serve the next steps' mixing."""
        o = self.pb.options
        if not o.anderson_reuse:
            return
        new = [(b - a, d - c) for a, b, c, d in zip(xs[:-1], xs[1:], gs[:-1], gs[1:])]
        self.kept = (new[::-1] + self.kept)[:o.anderson_depth * o.anderson_reuse]

    def _fields_off(self, rtol: float | None) -> dict:
        pb = self.pb
        return fields_off(self.field_increments, pb.layout.field_owned, rtol, pb.options.newton_increment_floor)

    def error_bound(self, xs: list, gs: list) -> float:
        """Bound of the distance of G(x_k) = gs[-1] from the step's solution in the max norm relative to each field
        (_weights): rho / (1 - rho) ||G(x_k) - x_k||, rho the largest secant ratio
        ||G(x_j) - G(x_j-1)|| / ||x_j - x_j-1|| of the owned iterates `xs` and their sweeps `gs` and of the previous
        step (self.contraction); inf before two sweeps or when rho >= 1, 0 at a fixed point."""
        w = self._weights()
        local = [np.abs((gs[-1] - xs[-1]) * w).max(initial=0.0)]
        for j in range(1, len(xs)):
            local += [np.abs((gs[j] - gs[j - 1]) * w).max(initial=0.0),
                      np.abs((xs[j] - xs[j - 1]) * w).max(initial=0.0)]
        total = np.empty(len(local))
        self.pb.comm.Allreduce(np.array(local), total, op=MPI.MAX)
        change, pairs = total[0], total[1:].reshape(-1, 2)
        if change == 0.0:
            return 0.0
        ratios = [dg / dx for dg, dx in pairs if dx > 0.0]
        if not ratios:
            return math.inf
        self.step_contraction = max(ratios)
        rho = max(self.step_contraction, self.contraction)
        return rho / (1.0 - rho) * change if rho < 1.0 else math.inf

    def mix(self, xs: list, gs: list) -> bool:
        """Move the state to Anderson's mixing of the sweeps `xs` -> `gs` (_anderson), where there is one to make
        (anderson_depth > 0 and two sweeps or kept differences); returns whether it did."""
        o = self.pb.options
        if not (o.anderson_depth and (len(xs) > 1 or self.kept)):
            return False
        self.pb.x.x.array[:len(xs[-1])] = self._anderson(xs, gs, self._weights())
        self.pb.x.x.scatter_forward()
        return True

    def converged(self, xs: list, gs: list, r0: float, history: list) -> tuple[bool, bool, bool]:
        """The step's convergence test (module docstring) after a sweep: (converged, whether problem.b now holds the
        whole residual at the current state, whether the state is now the sweeps' mixing); `history` gets the
        residual it assembles. The residual test is made on the mixing (the next sweep's start, and the better
        state): where it fails, the residual it assembled is the next sweep's first wall rows."""
        pb, o = self.pb, self.pb.options
        if o.sweep_convergence == "contraction":
            self.bound = self.error_bound(xs, gs)
            if math.isfinite(self.bound):
                return self.bound <= (o.newton_field_rtol or o.newton_stol), False, False
            # no contraction to bound the error with (rho >= 1: Anderson's mixing carries the sweeps): Newton's test
        if self._fields_off(o.newton_field_rtol):
            return False, False, False
        mixed = self.mix(xs, gs)
        r = pb._assemble_residual()
        history.append(r)
        return math.isfinite(r) and (r <= o.newton_atol or r <= o.newton_rtol * r0), True, mixed

    def _check_accepted(self, r: float, sweeps: int, history: list) -> None:
        """A fixed point of the sweeps solves every row a block solves; the contraction test sees nothing else, the
        residual test hardly the kinematic rows. Refuse an accepted state whose residual is not finite or whose
        kinematic rows (outside the condensed wall's solve) do not hold."""
        if not math.isfinite(r):
            raise NewtonDivergence(f"non-finite residual after {sweeps} sweeps", history)
        if self.condensed:
            defect = self.kinematic_defect()
            if defect > self.pb.options.newton_increment_floor:
                self.invalidate()
                raise NewtonDivergence(f"the sweeps' fixed point breaks the solids' kinematic rows (|M^-1 r_U| = "
                                       f"{defect:.1e} m/s after {sweeps} sweeps)", history)
