# ureterfsi — reproduction of the stented-ureter FSI study.
#   snakemake --cores 2                 full reproduction (every figure of the paper)
#   snakemake --cores 2 all_meshes      every mesh of the configuration
#   snakemake --cores 2 all_figures     the figures (runs whatever is missing)
#   snakemake --cores 2 all_field_figures   the figures drawn from the field files
#   snakemake --report report.html      HTML report with every figure and its caption
# Configuration: config/config.yaml, validated against workflow/schemas/config.schema.yaml
# and by ureterfsi.config (geometric consistency) before any rule runs (workflow/rules/common.smk).
from snakemake.utils import min_version

min_version("9.0")


configfile: "config/config.yaml"


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/solve_functions.smk"
include: "workflow/rules/design_functions.smk"
include: "workflow/rules/mesh.smk"
include: "workflow/rules/solve.smk"
include: "workflow/rules/aggregate.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/fields.smk"
include: "workflow/rules/calibration.smk"
include: "workflow/rules/ladder.smk"
include: "workflow/rules/stability.smk"
include: "workflow/rules/designs.smk"


rule all:
    default_target: True
    input:
        rules.all_figures.input,
        rules.all_field_figures.input,
        rules.calibration.output,


# last: applies the site settings of a cluster run to every rule above
include: "workflow/rules/cluster.smk"
