# Design rule of the peristaltic load (paper §2.4.2: the Gaussian pulse gives ~1 mm wall deformation),
# checked by the solver on an axisymmetric wall-only model, and the calibration rule of the
# Mooney-Rivlin coefficients (ureterfsi.study.calibration). Cheap: a 2D r-z wall, ~1-2 min on one core.


rule calibration:
    output:
        paths.CALIBRATION,
    log:
        paths.log("calibration/wall_calibration"),
    benchmark:
        paths.benchmark("calibration/wall_calibration")
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,
    params:
        # rerun trigger and the only input: the configuration sections the study reads
        sections=lambda w: {
            k: config[k] for k in ("geometry", "ureter", "peristalsis", "time")
        },
    script:
        "../scripts/calibration.py"
