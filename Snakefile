# ureterfsi — reproduction of the stented-ureter FSI study.
#   snakemake --cores 2                 full reproduction (every figure of the paper)
#   snakemake --cores 2 all_meshes      every mesh of the configuration
#   snakemake --cores 2 all_figures     the figures (runs whatever is missing)
#   snakemake --report report.html      HTML report with every figure and its caption
# Configuration: config/config.yaml, validated against workflow/schemas/config.schema.yaml
# and by ureterfsi.config (geometric consistency) before any rule runs.
import sys

from snakemake.utils import min_version

min_version("9.0")


configfile: "config/config.yaml"


# Validation at the edge: one clear line naming the key and the constraint, non-zero exit, no output.
from ureterfsi.config import ConfigError, validate_config

try:
    validate_config(config)
except ConfigError as err:
    sys.stderr.write(f"{err}\n")
    sys.exit(2)


include: "workflow/rules/common.smk"
include: "workflow/rules/mesh.smk"
include: "workflow/rules/solve.smk"
include: "workflow/rules/aggregate.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/calibration.smk"
include: "workflow/rules/ladder.smk"
include: "workflow/rules/stability.smk"
include: "workflow/rules/designs.smk"


rule all:
    default_target: True
    input:
        rules.all_figures.input,
        rules.calibration.output,
