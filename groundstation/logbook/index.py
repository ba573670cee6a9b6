"""``report DIR``'s front page: every log of the folder, worst first, each linking to its flight report.

Worst first: by the most severe finding (high, medium, low, none), then by how many findings; a log that
could not be read comes first of all, with its error. Self-contained like the reports (no script, no
address outside the folder).
"""

from __future__ import annotations

from pathlib import Path

from groundstation.export.files import atomic_output
from groundstation.export.report_figures import escaped
from groundstation.export.report_findings import SEVERITIES

STYLE = ("body{font-family:sans-serif;margin:2em;max-width:72em} table{border-collapse:collapse} "
         "td,th{border-bottom:1px solid #ddd;padding:.3em .6em;text-align:left;vertical-align:top} "
         ".high{color:#b71c1c;font-weight:bold} .medium{color:#e65100} .low{color:#555} .error{color:#b71c1c}")


def worst_first(logs: list[dict]) -> list[dict]:
    def rank(log: dict) -> tuple:
        if log["error"]:
            return (-1, 0, log["path"])
        severity = SEVERITIES.index(log["worst_severity"]) if log["worst_severity"] in SEVERITIES else len(SEVERITIES)
        return (severity, -(log["findings"] or 0), log["path"])

    return sorted(logs, key=rank)


def write_index(rows: list[dict], path: Path) -> None:
    """``path``: a table of the logs in ``rows`` (a log's first row speaks for it), worst first."""
    logs = list({row["log_id"]: row for row in reversed(rows)}.values())
    body = []
    for log in worst_first(logs):
        name = escaped(log["path"])
        if log["error"]:
            body.append(f"<tr><td>{name}</td><td class=\"error\">cannot be read</td><td>{escaped(log['error'])}</td>"
                        "<td></td><td></td></tr>")
            continue
        severity = log["worst_severity"] or "none"
        link = f"<a href=\"reports/{log['log_id']}.html\">{name}</a>"
        duration = f"{log['duration_s']:.0f} s" if log["duration_s"] is not None else ""
        body.append(f"<tr><td>{link}</td><td class=\"{severity}\">{severity}</td>"
                    f"<td>{escaped(log['worst_finding'] or 'nothing found')} ({log['findings'] or 0} findings)</td>"
                    f"<td>{escaped(log['vehicle'] or '')}</td><td>{duration}</td></tr>")
    page = (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>Flight reports</title>"
            f"<style>{STYLE}</style></head><body><h1>Flight reports: {len(logs)} logs, worst first</h1>"
            "<table><tr><th>log</th><th>worst</th><th>finding</th><th>vehicle</th><th>duration</th></tr>"
            f"{''.join(body)}</table></body></html>")
    with atomic_output(path, overwrite=True) as temporary:
        Path(temporary).write_text(page, encoding="utf-8")
