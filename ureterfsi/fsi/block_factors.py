"""The kept LU factors of the partitioned scheme's blocks (partitioned.PartitionedCoupling): a diagonal block's LU
(MUMPS), and a block of one vector field's components factorised per component where it does not couple them."""
from __future__ import annotations

from petsc4py import PETSc

from .condensation import direct
from .linear_solvers import Mumps, mumps_status


class BlockFactor:
    """LU (MUMPS) of a diagonal block A[I, I] of a matrix, kept until `refresh`."""

    def __init__(self, comm, prefix: str, mumps: Mumps):
        self.ksp = direct(comm, prefix, "lu", mumps)
        self.block = None
        self.rate = None                  # b0/dt of the Jacobian it was factorised from

    def refresh(self, matrix: PETSc.Mat, index: PETSc.IS, rate: float) -> None:
        """Factorise matrix[index, index]."""
        self.factorise(matrix.createSubMatrix(index, index, submat=self.block), rate)

    def factorise(self, block: PETSc.Mat, rate: float) -> None:
        """Factorise `block` (kept as the operator)."""
        self.block = block
        self.ksp.setOperators(self.block)
        self.ksp.getPC().setReusePreconditioner(False)
        self.ksp.setUp()
        self.ksp.getPC().setUp()          # factorise now (KSP's own set-up would leave it to the first solve)
        self.rate = rate

    def solve(self, b: PETSc.Vec, x: PETSc.Vec) -> str:
        """x = A[I, I]^-1 b; returns why it failed ("" if it did not)."""
        self.ksp.solve(b, x)
        reason = self.ksp.getConvergedReason()
        if reason >= 0:
            return ""
        return f"LU failed (PETSc KSP reason {reason}{mumps_status(self.ksp.getPC().getFactorMatrix())})"


class ComponentFactor:
    """The interface of BlockFactor for a block whose unknowns are the components of one vector field (`components`:
    each component's positions in the block's split): where the block does not couple them, A[I_c, I_d] = 0 for
    c != d (the harmonic mesh extension, int k Grad u : Grad psi), one LU per component block A[I_c, I_c]: the same
    solution with a third of the whole block's factor and its solve; else (`decoupled` False) the whole block's LU."""

    DECOUPLED_RTOL = 1e-12        # ||A[I, I]||_F^2 - sum_c ||A[I_c, I_c]||_F^2 within this part of ||A[I, I]||_F^2

    def __init__(self, comm, prefix: str, mumps: Mumps, components: list):
        self.comm, self.prefix, self.mumps = comm, prefix, mumps
        self.components = components
        self.parts, self.subsets, self.work = [], [], []     # per component: BlockFactor, PETSc IS, (rhs, solution)
        self.whole = None                 # BlockFactor of the whole block, where it couples them
        self.decoupled = None
        self.rate = None

    def refresh(self, matrix: PETSc.Mat, index: PETSc.IS, rate: float) -> None:
        """Factorise matrix[index, index], per component where it does not couple them."""
        block = matrix.createSubMatrix(index, index)
        if not self.parts:
            indices = index.getIndices()
            self.subsets = [PETSc.IS().createGeneral(indices[p], comm=self.comm) for p in self.components]
            self.parts = [BlockFactor(self.comm, f"{self.prefix}{c}_", self.mumps)
                          for c in range(len(self.components))]
        blocks = [matrix.createSubMatrix(s, s, submat=f.block) for s, f in zip(self.subsets, self.parts)]
        total = block.norm(PETSc.NormType.FROBENIUS) ** 2
        coupling = total - sum(b.norm(PETSc.NormType.FROBENIUS) ** 2 for b in blocks)
        self.decoupled = coupling <= self.DECOUPLED_RTOL * total
        if self.decoupled:
            for factor, sub in zip(self.parts, blocks):
                factor.factorise(sub, rate)
            self.work = [(sub.createVecLeft(), sub.createVecRight()) for sub in blocks]
        else:
            self.whole = self.whole or BlockFactor(self.comm, self.prefix, self.mumps)
            self.whole.factorise(block, rate)
        self.rate = rate

    def solve(self, b: PETSc.Vec, x: PETSc.Vec) -> str:
        """x = A[I, I]^-1 b; returns why it failed ("" if it did not)."""
        if not self.decoupled:
            return self.whole.solve(b, x)
        rhs, out = b.array_r, x.array
        for factor, (bc, xc), positions in zip(self.parts, self.work, self.components):
            bc.array[:] = rhs[positions]
            failed = factor.solve(bc, xc)
            if failed:
                return failed
            out[positions] = xc.array_r
        return ""
