"""`lanekeep bench --junit FILE`: the bench as JUnit XML, the report format CI systems read
(GitLab, Jenkins, GitHub actions that publish test results).

One <testsuite> "lanekeep bench"; one <testcase> per episode (a scenario, or a scenario driven
by one front model alone, "SCENARIO@MODEL"), its time the episode's wall time:
  - a failed criterion (lanekeep/scoring/criteria.py), the car off the road or in a collision
    among them: <failure>, its message naming each failed criterion with value and limit, its
    text the episode's table;
  - physics that went unstable, an episode stopped part-way (an interrupted bench): <error>
    of type "unstable" / "interrupted" (the run broke off, it did not fail);
  - an episode that never ran (an interrupted bench): <skipped>.
The layout is the common JUnit one (Ant's junit task, Jenkins' schema);
tests/report/test_junit.py validates against an XSD of it.
"""

from __future__ import annotations

import socket
import xml.etree.ElementTree as ET
from datetime import UTC, datetime
from pathlib import Path

from lanekeep.core.files import atomic_path
from lanekeep.scoring.criteria import failure_message
from lanekeep.scoring.metrics import EpisodeReport

SUITE = "lanekeep bench"


def _case(label: str, report: EpisodeReport | None) -> ET.Element:
    case = ET.Element("testcase", name=label, classname=f"lanekeep.bench.{label.split('@')[0]}")
    if report is None:
        case.set("time", "0")
        ET.SubElement(case, "skipped", message="not run: the bench was interrupted")
        return case
    case.set("time", f"{report.wall_s:.3f}")
    if report.status in ("unstable", "interrupted"):  # the run broke off; it did not fail
        error = ET.SubElement(case, "error", message=report.stop_reason or report.status,
                              type=report.status)
        error.text = report.stop_reason
    elif not report.passed or report.status != "completed":
        message = failure_message(report) or f"status {report.status}"
        failure = ET.SubElement(case, "failure", message=message, type="criteria")
        failure.text = "\n".join(v.line() for v in report.failed_criteria()) or message
    out = ET.SubElement(case, "system-out")
    out.text = (f"seed {report.seed}, {report.steps} steps, {report.duration_s:.1f} s simulated, "
                f"status {report.status}\n{report.table()}\n")
    return case


def junit_tree(reports: dict[str, EpisodeReport | None], wall_s: float) -> ET.ElementTree:
    """The JUnit document of a bench: `reports` by label in the jobs' order (None: not run)."""
    cases = [_case(label, report) for label, report in reports.items()]
    count = {tag: sum(1 for c in cases if c.find(tag) is not None)
             for tag in ("failure", "error", "skipped")}
    attrs = {"name": SUITE, "tests": str(len(cases)), "failures": str(count["failure"]),
             "errors": str(count["error"]), "time": f"{wall_s:.3f}"}
    root = ET.Element("testsuites", attrs)
    now = datetime.now(UTC).replace(tzinfo=None)  # JUnit's timestamp has no zone: UTC
    suite = ET.SubElement(root, "testsuite", {
        **attrs, "skipped": str(count["skipped"]), "timestamp": now.isoformat(timespec="seconds"),
        "hostname": socket.gethostname() or "localhost",
    })
    suite.extend(cases)
    ET.indent(root)
    return ET.ElementTree(root)


def write_junit(path: str | Path, reports: dict[str, EpisodeReport | None], wall_s: float
                ) -> Path:
    """Write the JUnit XML of a bench to `path` atomically (a temporary file, then renamed),
    the folder created if missing. Returns the path."""
    path = Path(path)
    tree = junit_tree(reports, wall_s)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tree.write(tmp, encoding="utf-8", xml_declaration=True)
    return path
