"""The workflow's code standard: `snakemake --lint` finds only the conda/container class (dolfinx
comes from Debian's packages, README), and snakefmt would change no Snakefile or rule file."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SOFTWARE_LINT = "Specify a conda environment or container for each rule."
LINT_TITLE = re.compile(r"^    \* (.+?):?$", re.M)


def lint_titles(snakefile: Path, cwd: Path) -> list[str]:
    """The title of every lint `snakemake --lint` reports for `snakefile` (Snakemake 9.27 prints text only:
    its JSON form is not passed on by the command line)."""
    run = subprocess.run([sys.executable, "-m", "snakemake", "--lint", "--snakefile", str(snakefile)], cwd=cwd,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode in (0, 1), run.stderr[-3000:]
    return LINT_TITLE.findall(run.stdout + run.stderr)


def test_lint_leaves_only_the_software_deployment_class():
    titles = lint_titles(REPO / "Snakefile", REPO)
    assert titles and set(titles) == {SOFTWARE_LINT}, sorted(set(titles))


def test_lint_titles_catch_the_other_classes(tmp_path):
    """The parser sees what the workflow must not have: functions beside rules, an absolute path, a long run
    directive."""
    body = "\n".join(f"        x{i} = len(str(input)) + {i}" for i in range(40))
    (tmp_path / "rules.smk").write_text(
        'def f(w):\n    return "/etc/hostname"\n\n\n'
        f'rule a:\n    output:\n        "a.txt",\n    log:\n        "a.log",\n    run:\n{body}\n')
    (tmp_path / "Snakefile").write_text('include: "rules.smk"\n')
    titles = lint_titles(tmp_path / "Snakefile", tmp_path)
    assert "Mixed rules and functions in same snakefile." in titles, titles
    assert any(t.startswith('Absolute path "/etc/hostname"') for t in titles), titles
    assert "Migrate long run directives into scripts or notebooks" in titles, titles


def test_snakefmt_would_change_nothing():
    run = subprocess.run([sys.executable, "-m", "snakefmt", "--check", "."], cwd=REPO, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "would be left unchanged" in run.stderr + run.stdout
