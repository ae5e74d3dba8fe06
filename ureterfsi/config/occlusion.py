"""Where a complete occlusion (geometry.occlusion_length > 0, ureterfsi.mesh.geometry.Occlusion) can be posed: its
span and its company in the geometry (check_occlusion), the models it cannot be posed on (occlusion_unposable) and
the one-way rung it refuses (check_occlusion_rungs)."""
from __future__ import annotations

from ureterfsi.mesh.geometry import StentModel, UreterGeometry, occluded_holes

from .errors import ConfigError, fmt


def check_occlusion(cfg):
    """A complete occlusion (geometry.occlusion_length > 0, ureterfsi.mesh.geometry.Occlusion) and its tapers lie inside
    the segment, apart from the clamped end faces; it is the only narrowing (no stricture) of a coaxial stent
    (the wall ties onto it all round). A model it cannot pose (stent-free, or a hole under its span) is refused where
    its mesh is asked for (runs.unmakeable), the one-way rung by check_occlusion_rungs."""
    g, geo = cfg["geometry"], UreterGeometry.from_config(cfg)
    if not geo.occluded:
        return
    lo, hi = geo.occlusion.span
    if not (lo > 0.0 and hi < g["length"]):
        raise ConfigError("geometry.occlusion_position",
                          f"the occlusion with its tapers [{fmt(lo)}, {fmt(hi)}] m (occlusion_position -+ "
                          f"(occlusion_length/2 + occlusion_taper)) must lie inside the segment (0, {fmt(g['length'])}) "
                          f"m, "
                          f"apart from the clamped end faces")
    if geo.strictured:
        raise ConfigError("geometry.occlusion_length", "a complete occlusion is the segment's narrowing: set "
                                                       "geometry.stricture_fraction to 0 (one or the other)")
    if geo.stent_offset:
        raise ConfigError("geometry.occlusion_length", f"a complete occlusion ties the wall onto a coaxial stent all "
                                                       f"round: geometry.stent_offset must be 0, got "
                                                       f"{fmt(geo.stent_offset)}")


def occlusion_unposable(cfg: dict, model: str) -> str:
    """Why a complete occlusion (geometry.occlusion_length > 0) cannot be posed on `model`, '' if it can (or there
    is none): a stent-free model (the wall would close the ureter), a side-hole pair under the occlusion's span (the
    wall closes a hole under the contact; under a taper the hole opens into a wedge thinner than itself)."""
    geo, sm = UreterGeometry.from_config(cfg), StentModel.from_config(cfg, model)
    if not geo.occluded:
        return ""
    if not sm.stent:
        return (f"model {model} has no stent: a complete occlusion (geometry.occlusion_length > 0) closes the annulus "
                f"onto the stent, without one it would close the ureter")
    z = occluded_holes(geo, sm)
    if z.size:
        lo, hi = geo.occlusion.span
        return (f"model {model}: the side-hole pair at z = {fmt(float(z[0]))} m lies under the occlusion's span "
                f"[{fmt(lo)}, {fmt(hi)}] m (occlusion_position -+ (occlusion_length/2 + occlusion_taper)); move the "
                f"occlusion or the holes")
    return ""


def check_occlusion_rungs(cfg):
    """Under a complete occlusion every stented model's study run is fully coupled: the one-way rung's r-z wall
    moves freely where the 3D wall is tied to the stent (ureterfsi.study.oneway refuses it too)."""
    if not cfg["geometry"]["occlusion_length"]:
        return
    for name in sorted(cfg["models"], key=int):
        over = cfg["study"]["runs"].get(name, {})
        if not occlusion_unposable(cfg, name) and over.get("fidelity", cfg["study"]["fidelity"]) == "one_way":
            key = f"study.runs.{name}.fidelity" if "fidelity" in over else "study.fidelity"
            raise ConfigError(key, f"one_way cannot pose the complete occlusion (geometry.occlusion_length > 0) of "
                                   f"model {name}: its r-z wall ignores the tie to the stent; use fully_coupled")
