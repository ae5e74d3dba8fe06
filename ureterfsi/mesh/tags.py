"""Integer tags of subdomains (cells) and boundaries (facets) shared by every mesh of the project.

Cell tags name physical regions; facet tags name boundaries and interfaces. Every boundary facet
carries exactly one facet tag; interfaces between subdomains are tagged facets too. The r-z wall-only scene
(ureterfsi.scenes.wall_rz) carries the ureter wall's tags: URETER; FLUID_URETER, URETER_OUTER, URETER_ENDS.
"""

# Cells (gmsh physical volumes in 3D, physical surfaces in 2D)
FLUID = 1           # urine: lumen around the stent, stent lumen, side-hole channels
URETER = 2          # ureter wall (hyperelastic)
STENT = 3           # stent wall (linear elastic)

# Facets
INLET = 11          # fluid open boundary at z = 0 (kidney side)
OUTLET = 12         # fluid open boundary at z = L (bladder side)
URETER_OUTER = 13   # ureter outer surface, carries the peristaltic load
URETER_ENDS = 14    # ureter end faces z = 0, z = L (fixed)
STENT_ENDS = 15     # stent end faces z = 0, z = L (fixed)
FLUID_URETER = 16   # interface fluid / ureter inner wall
FLUID_STENT = 17    # interface fluid / stent (outer wall, lumen wall, hole walls)
SYMMETRY_X = 18     # mirror plane x = 0 (normal along x)
SYMMETRY_Y = 19     # mirror plane y = 0 (normal along y)
AXIS = 20           # symmetry axis r = 0 of the axisymmetric (r-z) model
URETER_STENT = 21   # interface ureter inner wall / stent outer wall under a complete occlusion (tied: shared nodes)

CELL_NAMES = {FLUID: "fluid", URETER: "ureter", STENT: "stent"}
FACET_NAMES = {
    INLET: "inlet", OUTLET: "outlet", URETER_OUTER: "ureter_outer", URETER_ENDS: "ureter_ends",
    STENT_ENDS: "stent_ends", FLUID_URETER: "fluid_ureter", FLUID_STENT: "fluid_stent",
    SYMMETRY_X: "symmetry_x", SYMMETRY_Y: "symmetry_y", AXIS: "axis", URETER_STENT: "ureter_stent",
}
