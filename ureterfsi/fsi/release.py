"""Release of the PETSc objects an engine object holds (MonolithicFSI.close): matrices, vectors, KSPs with
their preconditioners and LU factors (MUMPS), index sets.

petsc4py 3.18 never destroys an object Python collects: it stashes it in its communicator's garbage, which only a
collective PETSc.garbage_cleanup(comm) frees, and a communicator that is gone (a dolfinx mesh's own) leaves its
garbage resident for the process's life. The engine therefore destroys what it holds explicitly (`destroy_held`)
and empties its communicator's garbage (`collect_garbage`) when a problem is closed."""
from __future__ import annotations

from dolfinx import fem
from petsc4py import PETSc

PACKAGE = __name__.split(".")[0]


def destroy_held(owner: object, keep=()) -> None:
    """Destroy every PETSc object reachable from `owner` through the attributes of engine objects (instances of
    classes defined in this package) and the dicts, lists and tuples among them, and the PETSc vectors of the
    dolfinx functions found there (their arrays stay readable). Other objects of other libraries
    (forms, meshes) are not entered, nor the objects in `keep` (what the owner was given, e.g. a scene)."""
    seen, stack = {id(k) for k in keep}, [owner]
    while stack:
        obj = stack.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        if isinstance(obj, PETSc.Object):
            if obj.handle and not PETSc.Sys.isFinalized():
                obj.destroy()
        elif isinstance(obj, fem.Function):
            stack.append(obj.vector)
        elif isinstance(obj, dict):
            stack.extend(obj.values())
        elif isinstance(obj, (list, tuple)):
            stack.extend(obj)
        elif type(obj).__module__.split(".")[0] == PACKAGE and hasattr(obj, "__dict__"):
            stack.extend(vars(obj).values())


def collect_garbage(comm) -> None:
    """Destroy the PETSc objects Python has dropped on `comm` (collective over it)."""
    if not PETSc.Sys.isFinalized():
        PETSc.garbage_cleanup(comm)
