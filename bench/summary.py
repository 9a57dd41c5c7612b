#!/usr/bin/env python3
"""The README's benchmark summary, generated from the two reports.

Reads bench/REPORT.md (reconstruction) and bench/lod/REPORT.md (LOD), both
written by the benchmark programs, and writes a short markdown section:
scan2lod against the best peer for reconstruction time and fidelity and, per
level, for LOD extraction time and fidelity, then the cluster hierarchy's
uniform cuts against meshopt_simplify and the most faithful peer (when the LOD
report has them; older reports do not), with each report's date, machine and
source revision.

    bench/summary.py                       print the section
    bench/summary.py --readme README.md    rewrite it in place, between
                                           <!-- bench-summary:begin ... --> and
                                           <!-- bench-summary:end -->

It reads the reports' tables by their header cells and fails, naming the
report and the table, when one is missing, so a changed report format cannot
silently produce a stale or empty summary. Python 3 standard library only.
"""

import argparse
import math
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
BEGIN = "<!-- bench-summary:begin"
END = "<!-- bench-summary:end -->"


class ReportError(Exception):
    pass


# ---------------------------------------------------------------------------
# Reading a report.


class Report:
    def __init__(self, path):
        self.path = path
        with open(path, encoding="utf-8") as f:
            self.lines = f.read().splitlines()

    def fail(self, what):
        raise ReportError(f"{self.path}: {what}")

    def header(self):
        """(date, machine) from the line under the title: 'date · arch · nproc N · cpu · load …'."""
        for line in self.lines[1:6]:
            if " · " in line:
                parts = [p.strip() for p in line.split(" · ")]
                machine = [p for p in parts[1:] if not p.startswith("load average")]
                return parts[0], " · ".join(machine)
        self.fail("no 'date · machine' line under the title")

    def field(self, name):
        """The text after 'Name: ' on a line of the report's preamble, or ''."""
        for line in self.lines[:20]:
            if line.startswith(name + ": "):
                return line[len(name) + 2:].strip()
        return ""

    def tables(self):
        """Every markdown table as (section heading, header cells, rows of cells)."""
        out, heading, i = [], "", 0
        while i < len(self.lines):
            line = self.lines[i]
            if line.startswith("#"):
                heading = line.lstrip("#").strip()
            if line.startswith("|") and i + 1 < len(self.lines) and self.lines[i + 1].startswith("|--"):
                header = cells(line)
                rows = []
                i += 2
                while i < len(self.lines) and self.lines[i].startswith("|"):
                    rows.append(cells(self.lines[i]))
                    i += 1
                out.append((heading, header, rows))
                continue
            i += 1
        return out

    def table(self, heading_starts, first_cells):
        """The first table under a heading starting with heading_starts whose
        header begins with first_cells, as a list of dicts keyed by header."""
        for heading, header, rows in self.tables():
            if heading.startswith(heading_starts) and header[: len(first_cells)] == first_cells:
                return [dict(zip(header, r)) for r in rows]
        self.fail(f"no table '{' | '.join(first_cells)} …' under '{heading_starts}'")

    def sentence_after(self, heading_starts, starts):
        """The first line starting with `starts` under a heading starting with heading_starts."""
        heading = ""
        for line in self.lines:
            if line.startswith("#"):
                heading = line.lstrip("#").strip()
            elif heading.startswith(heading_starts) and line.startswith(starts):
                return line
        return ""


def cells(line):
    return [c.strip() for c in line.strip().strip("|").split("|")]


def plain(cell):
    return cell.replace("**", "").strip()


def number(cell):
    """The number a cell starts with ('0.18 (0.17–0.18, 5 runs)', '**0.9237**',
    '0.0053 [336016]'), or None for a status ('killed at …', 'skipped …', '—')."""
    m = re.match(r"^([0-9]+(?:\.[0-9]+)?)(?:\s|$|\[|\()", plain(cell))
    return float(m.group(1)) if m else None


def comparable_r(setting):
    """The scan2lod R a setting compares with: R=n, n samples/side, depth d -> 2^d."""
    m = re.match(r"R=(\d+)", setting)
    if m:
        return int(m.group(1))
    m = re.match(r"(\d+) samples/side", setting)
    if m:
        return int(m.group(1))
    m = re.match(r"depth (\d+)", setting)
    if m:
        return 2 ** int(m.group(1))
    return None


def times(x):
    """A ratio as '2.1×', '116×'."""
    return f"{x:.1f}×" if x < 10 else f"{x:.0f}×"


def faster(ratio):
    """Peer seconds / scan2lod seconds, in words."""
    return f"**{times(ratio)} faster**" if ratio >= 1 else f"**{times(1 / ratio)} slower**"


def error_ratio(ours, peer):
    """scan2lod's error / the peer's, in words."""
    return ratio_words(ours / peer)


def ratio_words(r):
    """An error ratio, scan2lod's / the peer's, in words."""
    if r >= 1:
        return f"**{r:.2f}× the peer's**" if r < 10 else f"**{r:.0f}× the peer's**"
    return f"**{1 / r:.2f}× lower**" if 1 / r < 10 else f"**{1 / r:.0f}× lower**"


def growth(report, heading, keep):
    """The growth line of a scaling table, its items whose names are in `keep`:
    'seconds ×3.41, peak MiB ×2.40', or ''."""
    line = report.sentence_after(heading, "Growth per doubling")
    m = re.search(r"here\): (.*?)\. A dense grid", line)
    if not m:
        return ""
    items = [i.strip() for i in m.group(1).split(", ")]
    return ", ".join(i for i in items if i.rsplit(" ×", 1)[0] in keep)


def resolutions(report, heading):
    """'64 to 512': the R column's first and last rows of a scaling table, or ''."""
    try:
        rows = report.table(heading, ["R"])
    except ReportError:
        return ""
    return f"{rows[0]['R']} to {rows[-1]['R']}" if rows else ""


def provenance(report, name):
    date, machine = report.header()
    source = report.field("Source").replace(" (at run time)", "")
    return f"`{name}`: {date}, {machine}" + (f", source {source}" if source else "")


# ---------------------------------------------------------------------------
# The two sections.


def reconstruction_section(report):
    rows = report.table("Every method", ["method", "setting", "seconds (median)"])
    ours, peers, unfinished = {}, [], []
    for r in rows:
        method, setting = plain(r["method"]), r["setting"]
        seconds = number(r["seconds (median)"])
        # Reports from before the two-sided column: the mean of the rounded directions.
        mean = re.findall(r"[0-9.]+", r.get("mean % (out→ref / ref→out)", ""))
        two_sided = number(r["two-sided mean %"]) if "two-sided mean %" in r else (
            (float(mean[0]) + float(mean[1])) / 2 if len(mean) == 2 else None)
        entry = {"name": f"{method} {setting}", "setting": setting, "seconds": seconds, "error": two_sided,
                 "digits": 4 if "two-sided mean %" in r else 3}
        if method == "scan2lod reconstruct()":
            ours[comparable_r(setting)] = entry
        elif not method.startswith("scan2lod"):
            entry["r"] = comparable_r(setting)
            if seconds is None:
                status = r["seconds (median)"]
                if not status.startswith("skipped"):
                    unfinished.append(f"{entry['name']} ({status})")
            else:
                peers.append(entry)

    out = []
    timed = [p for p in peers if ours.get(p["r"], {}).get("seconds")]
    if timed:
        best = min(timed, key=lambda p: p["seconds"] / ours[p["r"]]["seconds"])
        own = ours[best["r"]]
        out.append(f"| reconstruction time | {own['seconds']:.2f} s ({own['setting']}) | "
                   f"{best['name']}: {best['seconds']:.2f} s | {faster(best['seconds'] / own['seconds'])} |")
    else:
        out.append("| reconstruction time | — | no peer finished beside a scan2lod case | — |")
    measured = [p for p in peers if p["error"] is not None and ours.get(p["r"], {}).get("error") is not None]
    if measured:
        best = min(measured, key=lambda p: p["error"])
        own = ours[best["r"]]
        out.append(f"| reconstruction fidelity: two-sided mean distance to the reference, % of its diagonal | "
                   f"{own['error']:.{own['digits']}f} % ({own['setting']}) | {best['name']}: "
                   f"{best['error']:.{best['digits']}f} % | "
                   f"error {error_ratio(own['error'], best['error'])} |")
    else:
        out.append("| reconstruction fidelity | — | no peer measured beside a scan2lod case | — |")
    return out, unfinished


def lod_section(report):
    """Per level, from the peer tables under '### P % of the LOD array: T triangles'
    (their error ratios are computed from unrounded errors; the rounded errors of
    the finest peers would not give them)."""
    build = report.table("Model build", ["stage"])
    model = next((r["seconds (median, range)"] for r in build if "model build" in r["stage"]), "")
    model_seconds = number(model)
    runs = re.search(r"(\d+) runs?\)", model)
    model_text = (f"{model_seconds:.2f} s" + (f", median of {runs.group(1)} runs" if runs and runs.group(1) != "1" else "")
                  if model_seconds is not None else plain(model) or "—")

    out, unfinished = [], set()
    for heading, header, rows in report.tables():
        level = re.match(r"(\d+ %) of the LOD array: (\d+) triangles", heading)
        if not level or header[:4] != ["method", "kind", "triangles", "seconds (median, range)"]:
            continue
        table = [dict(zip(header, r)) for r in rows]
        own = next((r for r in table if "scan2lod" in r["method"]), None)
        if own is None:
            report.fail(f"no scan2lod row under '{heading}'")
        own_seconds = number(own["seconds (median, range)"])
        own_error = number(own["error (1e-3 diag)"])
        timed, measured = [], []
        for r in table:
            if r is own:
                continue
            name, seconds = plain(r["method"]), number(r["seconds (median, range)"])
            if seconds is None:
                if not r["seconds (median, range)"].startswith("skipped"):
                    unfinished.add(f"{name} ({r['seconds (median, range)']})")
                continue
            timed.append((seconds, name))
            error, ratio = number(r["error (1e-3 diag)"]), number(r["error ratio"])
            if error is not None and ratio is not None:
                measured.append((ratio, error, name))
        if timed and own_seconds:
            s, n = min(timed)
            time_cells = f"{own_seconds * 1e3:.2f} ms | {n}: {s * 1e3:.0f} ms | {faster(s / own_seconds)}"
        else:
            time_cells = f"{'—' if own_seconds is None else f'{own_seconds * 1e3:.2f} ms'} | — | —"
        if measured and own_error is not None:
            ratio, e, n = max(measured)  # the largest ratio: the most faithful peer
            error_cells = f"{own_error:.4f} | {n}: {e:.4f} | {ratio_words(ratio)}"
        else:
            error_cells = f"{'—' if own_error is None else f'{own_error:.4f}'} | — | —"
        out.append(f"| {level.group(1)} | {level.group(2)} | {time_cells} | {error_cells} |")
    if not out:
        report.fail("no per-level peer tables ('### P % of the LOD array: T triangles')")
    return out, model_text, sorted(unfinished)


def budget_section(report):
    """The octree at `--triangles` budgets against the vertex-clustering peers
    at its count, from the tables under '### budget 1k (`--triangles`): T triangles'."""
    clustering = ["meshopt_simplifySloppy", "Open3D VertexClustering", "VTK QuadricClustering"]
    out = []
    for heading, header, rows in report.tables():
        level = re.match(r"budget (\d+k) \(`--triangles`\): (\d+) triangles", heading)
        if not level or header[:4] != ["method", "kind", "triangles", "seconds (median, range)"]:
            continue
        table = {plain(r[0]): dict(zip(header, r)) for r in rows}
        own = next((r for name, r in table.items() if "scan2lod" in name), None)
        own_error = number(own["error (1e-3 diag)"]) if own else None
        if own_error is None:
            continue
        cells_out = []
        for name in clustering:
            r = table.get(name)
            e = number(r["error (1e-3 diag)"]) if r else None
            t = number(r["triangles"]) if r else None
            cells_out.append("—" if e is None else f"{e:.4f}" + (f" [{t:.0f}]" if t and abs(t - float(level.group(2))) > 0.01 * float(level.group(2)) else "") + f" ({error_ratio(own_error, e)})")
        out.append(f"| {level.group(1)} | {level.group(2)} | {own_error:.4f} | " + " | ".join(cells_out) + " |")
    return out


def cluster_section(report):
    """The cluster hierarchy's uniform cuts against meshopt_simplify and the
    best peer, from the table under 'Cluster hierarchy beside the octree', and
    its build, storage and selection figures; ([], "") for a report from
    before the cluster hierarchy."""
    try:
        facts = report.table("Cluster hierarchy", ["cluster hierarchy", "value"])
        cuts = report.table("Cluster hierarchy", ["budget", "cut triangles", "clusters"])
    except ReportError:
        return [], ""
    out = []
    for r in cuts:
        own = number(r["cluster cut"])
        if own is None:
            continue
        simplify = number(r.get("meshopt_simplify", ""))
        # The most faithful peer and the ratio to it, as the report computed them from unrounded errors.
        best_name, to_best = plain(r["most faithful peer"]), number(r["cut / it"])
        best_error = number(r.get(best_name, ""))
        best = (f"{best_name}: {best_error:.4f} | {ratio_words(to_best)}"
                if to_best is not None and best_error is not None else "— | —")
        out.append(f"| {r['budget']} | {plain(r['cut triangles'])} | {own:.4f} | "
                   f"{'—' if simplify is None else f'{simplify:.4f}'} | "
                   f"{plain(r['cut / meshopt_simplify'])} | {best} |")
    value = {plain(r["cluster hierarchy"]): plain(r["value"]) for r in facts}
    def find(start):
        return next((v for k, v in value.items() if k.startswith(start)), "—")
    line = (f"Cluster hierarchy: build {find('build alone / ')} a whole-mesh `meshopt_simplify` to 1 %, "
            f"stored triangles {find('stored triangles').split('= ')[-1]} the full mesh's, coarsest cut "
            f"{find('coarsest cut')} triangles, view-dependent selection {find('view-dependent selection')} ms "
            f"(median; slowest camera).")
    return out, line


def summary(reconstruction_path, lod_path):
    recon = Report(reconstruction_path)
    lod = Report(lod_path)
    recon_rows, recon_unfinished = reconstruction_section(recon)
    lod_rows, model_build, lod_unfinished = lod_section(lod)
    lod_input = lod.field("Input")
    m = re.search(r"R = (\d+)", lod_input)
    lod_r = f" at R = {m.group(1)}" if m else ""

    out = ["Reconstruction from the bunny scans' oriented points, against the best of PCL's marching "
           "cubes and Poisson, Open3D's Poisson and VTK's surface reconstruction (time: the peer "
           "closest in speed, each at the setting comparable to scan2lod's R; fidelity: the most "
           "faithful peer, against scan2lod at its comparable R):",
           "",
           "| measure | scan2lod | best peer | scan2lod against it |",
           "|---|---:|---|---|"]
    out += recon_rows
    out.append("")
    scaling = growth(recon, "Scaling of scan2lod reconstruct()", {"seconds", "peak MiB", "cubes touched"})
    model_scaling = growth(recon, "Scaling of the LOD model build",
                           {"model build seconds", "points → model seconds", "build peak MiB"})
    if scaling or model_scaling:
        parts = [f"`reconstruct()` {scaling}" if scaling else "", model_scaling]
        out.append(f"Growth per doubling of R, {resolutions(recon, 'Scaling of scan2lod reconstruct()')} "
                   f"(a dense grid grows ×8, a surface ×4): " + "; ".join(p for p in parts if p) + ".")
        out.append("")
    out += [f"LOD{lod_r}: the model is built once (model build {model_build}; "
            "the peers have no build step), then each level is extracted by reference. Against the fastest "
            "and the most faithful of meshoptimizer, OpenMesh, VTK and Open3D simplifying the same full mesh "
            "to the same triangle count (error: two-sided mean distance to the full mesh, 1e-3 of its "
            "diagonal):",
            "",
            "| level | triangles | `extract_lod` | fastest peer | scan2lod against it | scan2lod error "
            "| most faithful peer | scan2lod's error against it |",
            "|---:|---:|---:|---|---|---:|---|---|"]
    out += lod_rows
    out.append("")
    budget_rows = budget_section(lod)
    if budget_rows:
        out += ["The octree's coarse end as `--triangles` gives it, against the vertex-clustering peers at its "
                "count (error as above; a peer's count in brackets where it is more than 1 % off; in parentheses "
                "the octree's error against it):",
                "",
                "| budget | triangles | octree error | meshopt_simplifySloppy | Open3D VertexClustering "
                "| VTK QuadricClustering |",
                "|---:|---:|---:|---|---|---|"]
        out += budget_rows
        out.append("")
    cluster_rows, cluster_line = cluster_section(lod)
    if cluster_rows:
        out += ["The cluster hierarchy's uniform cuts at triangle budgets (as `extract --triangles` gives them: a "
                "stored cut up to 1.25x the budget refined to it by edge collapse), against `meshopt_simplify` and "
                "the most faithful peer at the cut's count (error as above; the stored cuts alone: "
                "`bench/lod/REPORT.md`):",
                "",
                "| budget | triangles | cluster cut error | meshopt_simplify | cut / meshopt_simplify "
                "| most faithful peer | the cut's error against it |",
                "|---:|---:|---:|---:|---:|---|---|"]
        out += cluster_rows
        out.append("")
        out.append(cluster_line)
        out.append("")
    unfinished = recon_unfinished + lod_unfinished
    if unfinished:
        out.append("Did not finish (rows of their own in the reports): " + "; ".join(unfinished) + ".")
        out.append("")
    out.append(f"Measured by {provenance(recon, 'bench/REPORT.md')}; {provenance(lod, 'bench/lod/REPORT.md')}.")
    return "\n".join(out) + "\n"


def rewrite_readme(path, text):
    with open(path, encoding="utf-8") as f:
        readme = f.read()
    begin = readme.find(BEGIN)
    end = readme.find(END)
    if begin < 0 or end < begin:
        raise ReportError(f"{path}: no '{BEGIN} …' … '{END}' section to rewrite")
    begin_end = readme.index("-->", begin) + len("-->")
    new = readme[:begin_end] + "\n" + text + readme[end:]
    if new != readme:
        tmp = path + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(new)
        os.replace(tmp, path)
    print(f"summary.py: {'rewrote' if new != readme else 'unchanged:'} the summary in {path}", file=sys.stderr)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reconstruction", default=os.path.join(HERE, "REPORT.md"),
                        help="reconstruction report (default: bench/REPORT.md)")
    parser.add_argument("--lod", default=os.path.join(HERE, "lod", "REPORT.md"),
                        help="LOD report (default: bench/lod/REPORT.md)")
    parser.add_argument("--readme", help="rewrite the section between the bench-summary markers of this file")
    args = parser.parse_args()
    try:
        text = summary(args.reconstruction, args.lod)
        if args.readme:
            rewrite_readme(args.readme, text)
        else:
            sys.stdout.write(text)
    except (ReportError, OSError) as e:
        print(f"summary.py: error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
