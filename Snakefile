# ureterfsi — reproduction of the stented-ureter FSI study.
#   snakemake --cores 2                 full reproduction
#   snakemake --cores 2 all_meshes      every mesh of the configuration
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


rule all:
    input:
        rules.all_meshes.input,
    default_target: True
