"""Scenes posed to the generic FSI engine (ureterfsi.fsi).

ureter        the stented ureter (paper §2), and the urine alone of the one-way rung
wall_rz       the ureter wall alone in r-z: the calibration's and the one-way rung's wall step
turek_hron    the Turek-Hron FSI1-3 benchmarks (turek_hron_transient: FSI2/FSI3 in time)
verification  the problems with exact solutions (Poiseuille annulus, Mooney-Rivlin tube, hanging bar, confined
              column): verification.exact, their error norms and observed orders (.norms), their scenes by family
              (.flow, .tube, .weight, with .materials and .meshing)
"""

__all__ = ["turek_hron", "turek_hron_transient", "ureter", "verification", "wall_rz"]
