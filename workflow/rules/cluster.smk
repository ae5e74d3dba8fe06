# A cluster run (workflow/profiles/slurm) and the compute nodes it meets: config `cluster`, set by a site
# overlay (config/site-example.yaml). Included after every rule: each job gets the site's partition and
# account, and its tasks, mem_mb and runtime capped at what one node (and the partition) allows, so that no
# job waits in the queue for a node that cannot exist. Jobs that need more than a node has are refused before
# submission (common.smk: solve_mem_mb_of).
import os
import pwd

from ureterfsi.workflow.cluster import capped

# the SLURM plugin reads USER to guess an account; batch environments and CI containers may not set it
os.environ.setdefault("USER", pwd.getpwuid(os.getuid()).pw_name)


NODE_LIMITS = {
    "tasks": config["cluster"]["cpus_per_node"],
    "mem_mb": config["cluster"]["mem_mb_per_node"],
    "runtime": config["cluster"]["runtime_limit_min"],
}


# Not only where Snakemake submits (CLUSTER_RUN): the Snakemake inside a job plans the job's command again, with
# the same configuration, and must see the same capped ranks.
for _rule in workflow.rules:
    for _name, _value in (
        ("slurm_partition", config["cluster"]["partition"]),
        ("slurm_account", config["cluster"]["account"]),
    ):
        if _value is not None:
            _rule.resources[_name] = _value
    for _name, _limit in NODE_LIMITS.items():
        _resource = _rule.resources.get(_name)
        if _limit is not None and (
            _resource.is_evaluable() or _resource.value is not None
        ):
            _rule.resources[_name] = capped(_rule.resources[_name], _limit)
