"""The one table writer: rows as CSV (full precision) and as a Markdown table, each file atomically."""
from __future__ import annotations

import csv
import io

from ureterfsi.data.provenance import atomic_path


def write_table(rows: list[dict], csv_path=None, md_path=None, *, header=None, md_rows=None, footer=()) -> None:
    """`rows` (dicts with the same keys) to `csv_path` as CSV; to `md_path` as a Markdown table whose head is
    `header` (default: the keys) and whose cells are `md_rows` (default: str of each value), then `footer` lines
    after an empty line."""
    cols = list(rows[0])
    if csv_path:
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
        with atomic_path(csv_path) as tmp:
            tmp.write_text(buf.getvalue())
    if md_path:
        header = cols if header is None else header
        md_rows = [[str(r[c]) for c in cols] for r in rows] if md_rows is None else md_rows
        lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
        lines += ["| " + " | ".join(cells) + " |" for cells in md_rows]
        if footer:
            lines += ["", *footer]
        with atomic_path(md_path) as tmp:
            tmp.write_text("\n".join(lines) + "\n")
