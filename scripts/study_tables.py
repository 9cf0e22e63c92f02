"""Shared output of the study scripts: a CSV of result rows and a markdown
table of selected, formatted columns."""
from __future__ import annotations

import csv


def write_csv(path: str, rows: list[dict]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def markdown(columns: list[tuple[str, str, str]], rows: list[dict]) -> str:
    """``columns``: (header, row key, format spec) triples."""
    lines = ["| " + " | ".join(h for h, _, _ in columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        lines.append("| " + " | ".join(format(r[k], f) for _, k, f in columns) + " |")
    return "\n".join(lines)


def write_markdown(path: str, title: str, table: str) -> None:
    with open(path, "w") as f:
        f.write(f"# {title}\n\n{table}\n")
