#!/usr/bin/python3
"""Run a convergence study of bin/signorini from a YAML study file and report observed rates.

Usage: study.py STUDY.yaml [--outdir DIR] [--np N] [--dry-run] [--check] [--quiet]

The solver is run once per (series, level), in the repository root, as

    mpiexec -n NP bin/signorini [-options_file F] -key value ... -output DIR/<series>_<level>.h5

(plus `-reference DIR/<...>_ref.h5` when the study has reference runs). The /run attributes of
every output file are read back with read_runs.read_run, and DIR (default
output/studies/<name>/ in the repository) receives:

    <name>.csv          one row per run: series, level, the abscissa, every norm, newton_its,
                        ksp_its, time_solve, converged, exit_code, the observed rate of every norm
                        between this level and the previous one (rate_<norm>), file
    <name>.md           per series a table level by level (norms and level-to-level rates), then a
                        summary: series, norm, predicted exponent, fitted rate, agrees (yes/no)
    <name>_<norm>.png   log-log plot of the norm against the abscissa, all series, a dashed line of
                        each predicted slope through the finest point, fitted rates in the legend
    <series>_<level>.h5, .xdmf, .log   solver output and its console log (stdout and stderr)

Rates. Between consecutive levels, rate_k = log(e_k / e_{k-1}) / log(x_k / x_{k-1}). The fitted
rate is the least-squares slope of log e against log x over the last `fit_levels` levels. A rate
that needs a value that is not finite and positive (e.g. e = 0, or a signed quantity such as the
energy) is nan, and the tables say why; a fit is never silently restricted to the valid points.
A series agrees with its prediction p when fitted >= p - tolerance (one-sided: faster convergence
than predicted is agreement).

Study file (YAML). Keys marked * are required; any other top-level key is an error.

    name: rates2d            # * used in file names: letters, digits, '.', '_', '-'
    description: text        #   copied into the Markdown report
    np: 1                    #   MPI ranks per run (default 1; --np overrides)
    options_file: options/mms.yaml   # passed as -options_file to every run, before all options;
                             #   a relative path is relative to the repository root
    options:                 #   options of every run: key without the dash, value a string,
      dm_plex_dim: 2         #   number or boolean (booleans are passed as true/false)
    x: h                     # * /run attribute used as abscissa (h, eps, ...); must be > 0
    fit_levels: 3            #   the last N levels enter the fit (default: all levels; N >= 2)
    tolerance: 0.1           #   agreement: fitted >= predicted - tolerance (default 0.1)
    norms: [error_h1, error_pressure_weighted]   # * /run attributes tabulated, fitted, plotted
    series:                  # * a list; each series runs every level
      - label: nu=0.25       # * unique; the file-name stem replaces every character other than
                             #   letters, digits, '.', '-' by '_' (nu=0.25 -> nu_0.25)
        options: {mms_nu: 0.25}
        predicted: {error_h1: 0.6875}  # exponents; a norm without one is fitted, not judged
    levels:                  # * at least 2, coarsest first; options added to that level's runs
      - {dm_plex_box_faces: "8,8"}
      - {dm_plex_box_faces: "16,16"}
    # or, equivalently:  levels: {key: dm_plex_box_faces, values: ["8,8", "16,16"]}
    reference:               #   optional reference runs, passed as -reference FILE.h5
      options: {contact_method: vi}   # added to (and overriding) the run's own options
      per: level             #   "level" (default): one reference per (series, level), written to
                             #   <series>_<level>_ref.h5; "series": one per series, run with the
                             #   options of the LAST level, written to <series>_ref.h5
    checks:                  #   evaluated by --check
      - {type: rate, norms: [error_h1]}   # fitted >= predicted - tolerance, for every series that
                             #   predicts the norm (norms defaults to all norms; each listed norm
                             #   must be predicted by at least one series)
      - {type: monotone, norm: error_h1, floor_ratio: 0.9}   # see below (floor_ratio default 0.9)

Option precedence (later wins): options_file < study options < series options < level options
< reference options. `output` may not be set (the driver sets it), nor `reference` when the
study has a `reference:` section. Level indices are 0-based, coarsest first.

The monotone check, for each series, requires x to decrease along the levels and e to decrease,
e_k <= e_{k-1} (1 + 1e-6), until a floor. The floor starts at the first level k with
e_k > floor_ratio * e_{k-1}; its value is F = e_{k-1}, and from level k on every e must lie in
[F/2, 2F]. A series that never meets the floor condition just has to decrease.

Failed runs. A run that exits non-zero or writes converged = 0 is reported on stderr and in the
converged/exit_code columns; with --check it is a failed check. A run that exits non-zero without
writing its file stops the study, showing the tail of the solver's output.

Exit status: 0 success; 1 a check failed (--check); 2 an error (bad study file, a run that wrote
no output, an unreadable output file or a missing attribute).
"""
import argparse
import os
import re
import shlex
import sys
from dataclasses import dataclass
from typing import Optional

import numpy as np

SCRIPTS = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, SCRIPTS)
from signorini.figures import no_values_note, plt, save_png  # noqa: E402
from signorini.formatting import format_rate, format_value  # noqa: E402,F401
from signorini.mpirun import LOG_TAIL_LINES, MPI_ENV, run_mpi, tail  # noqa: E402,F401
from signorini.paths import BIN, ROOT, display_path  # noqa: E402,F401
from signorini.rates import (FLOOR_BAND, MONOTONE_RTOL, agrees, fitted_rate, invalid,  # noqa: E402,F401
                             level_rates, monotone_until_floor)
from signorini.report import md_options, md_row, md_rule, write_csv as write_csv_file, write_lines  # noqa: E402
from signorini.runs import read_run  # noqa: E402
from signorini.studyfile import (NAME_RE, StudyError, check_keys, number, option_value,  # noqa: E402,F401
                                 options, options_file, read_yaml, safe_label)

TOP_KEYS = ("name", "description", "np", "options_file", "options", "x", "fit_levels",
            "tolerance", "norms", "series", "levels", "reference", "checks")
REQUIRED_KEYS = ("name", "x", "norms", "series", "levels")
# ------------------------------------------------------------------------------ study file

def _levels(levels, where):
    """Expand `levels` (a list of option mappings, or {key, values}) to a list of option dicts."""
    if isinstance(levels, dict):
        check_keys(levels, ("key", "values"), ("key", "values"), where)
        if not isinstance(levels["values"], list):
            raise StudyError(f"{where}.values: expected a list")
        levels = [{levels["key"]: v} for v in levels["values"]]
    if not isinstance(levels, list):
        raise StudyError(f"{where}: expected a list of option mappings or {{key, values}}")
    if len(levels) < 2:
        raise StudyError(f"{where}: a convergence study needs at least 2 levels, got {len(levels)}")
    return [options(lev, f"{where}[{k}]") for k, lev in enumerate(levels)]


def _series(series, norms, where):
    """Validate the series list; return dicts with label, stem, options and predicted."""
    if not isinstance(series, list) or not series:
        raise StudyError(f"{where}: expected a non-empty list")
    out, stems = [], {}
    for i, s in enumerate(series):
        w = f"{where}[{i}]"
        check_keys(s, ("label", "options", "predicted"), ("label",), w)
        if not isinstance(s["label"], (str, int, float)) or isinstance(s["label"], bool):
            raise StudyError(f"{w}.label: expected a string, got {s['label']!r}")
        label = str(s["label"])
        stem = safe_label(label)
        if stem in stems:
            raise StudyError(f"{w}: label {label!r} gives the same file name '{stem}' as "
                             f"series {stems[stem]!r}")
        stems[stem] = label
        predicted = s.get("predicted") or {}
        if not isinstance(predicted, dict):
            raise StudyError(f"{w}.predicted: expected a mapping norm: exponent")
        for norm, p in predicted.items():
            if norm not in norms:
                raise StudyError(f"{w}.predicted: '{norm}' is not one of the study's norms "
                                 f"({', '.join(norms)})")
            number(p, f"{w}.predicted.{norm}")
        out.append({"label": label, "stem": stem, "options": options(s.get("options"), f"{w}.options"),
                    "predicted": {n: float(p) for n, p in predicted.items()}})
    return out


def _checks(checks, study, where):
    """Validate the checks list against the study's norms and predictions; return it normalized."""
    if checks is None:
        return []
    if not isinstance(checks, list):
        raise StudyError(f"{where}: expected a list")
    out = []
    for i, c in enumerate(checks):
        w = f"{where}[{i}]"
        if not isinstance(c, dict) or "type" not in c:
            raise StudyError(f"{w}: expected a mapping with a 'type' (rate or monotone)")
        if c["type"] == "rate":
            check_keys(c, ("type", "norms"), (), w)
            norms = c.get("norms", study["norms"])
            if not isinstance(norms, list) or not norms:
                raise StudyError(f"{w}.norms: expected a non-empty list")
            for norm in norms:
                if norm not in study["norms"]:
                    raise StudyError(f"{w}: '{norm}' is not one of the study's norms")
                if not any(norm in s["predicted"] for s in study["series"]):
                    raise StudyError(f"{w}: no series predicts a rate for '{norm}'")
            out.append({"type": "rate", "norms": list(norms)})
        elif c["type"] == "monotone":
            check_keys(c, ("type", "norm", "floor_ratio"), ("norm",), w)
            if c["norm"] not in study["norms"]:
                raise StudyError(f"{w}: '{c['norm']}' is not one of the study's norms")
            ratio = float(number(c.get("floor_ratio", 0.9), f"{w}.floor_ratio"))
            if ratio <= 0:
                raise StudyError(f"{w}.floor_ratio: must be > 0, got {ratio}")
            out.append({"type": "monotone", "norm": c["norm"], "floor_ratio": ratio})
        else:
            raise StudyError(f"{w}: unknown check type {c['type']!r} (rate or monotone)")
    return out


def load_study(path):
    """Read and validate a study file; return it normalized (see the module docstring).

    Every option value is converted to its command-line text, levels are expanded to a list of
    option dicts, and defaults are filled in. Raises StudyError naming the file and the key.
    """
    raw = read_yaml(path)
    check_keys(raw, TOP_KEYS, REQUIRED_KEYS, path)

    name = raw["name"]
    if not isinstance(name, str) or not re.fullmatch(NAME_RE, name):
        raise StudyError(f"{path}: name: {name!r} is not a file-name-safe string")
    norms = raw["norms"]
    if (not isinstance(norms, list) or not norms or not all(isinstance(n, str) for n in norms)
            or len(set(norms)) != len(norms)):
        raise StudyError(f"{path}: norms: expected a non-empty list of distinct attribute names")
    if not isinstance(raw["x"], str):
        raise StudyError(f"{path}: x: expected an attribute name such as h or eps")
    study = {
        "name": name,
        "description": str(raw.get("description", "")),
        "np": number(raw.get("np", 1), f"{path}: np", integer=True),
        "options_file": raw.get("options_file"),
        "options": options(raw.get("options"), f"{path}: options"),
        "x": raw["x"],
        "tolerance": float(number(raw.get("tolerance", 0.1), f"{path}: tolerance")),
        "norms": norms,
        "levels": _levels(raw["levels"], f"{path}: levels"),
    }
    study["series"] = _series(raw["series"], norms, f"{path}: series")
    if study["np"] < 1:
        raise StudyError(f"{path}: np: must be >= 1, got {study['np']}")
    if study["tolerance"] < 0:
        raise StudyError(f"{path}: tolerance: must be >= 0, got {study['tolerance']}")
    nlev = len(study["levels"])
    study["fit_levels"] = number(raw.get("fit_levels", nlev), f"{path}: fit_levels", integer=True)
    if not 2 <= study["fit_levels"] <= nlev:
        raise StudyError(f"{path}: fit_levels: must be between 2 and the number of levels "
                         f"({nlev}), got {study['fit_levels']}")

    options_file(study["options_file"], f"{path}: options_file")

    ref = raw.get("reference")
    if ref is not None:
        check_keys(ref, ("options", "per"), (), f"{path}: reference")
        per = ref.get("per", "level")
        if per not in ("level", "series"):
            raise StudyError(f"{path}: reference.per: must be 'level' or 'series', got {per!r}")
        ref = {"options": options(ref.get("options"), f"{path}: reference.options"), "per": per}
        scopes = [("options", study["options"])] + [
            (f"series {s['label']!r} options", s["options"]) for s in study["series"]] + [
            (f"levels[{k}]", lev) for k, lev in enumerate(study["levels"])]
        for where, opts in scopes:
            if "reference" in opts:
                raise StudyError(f"{path}: {where}: option 'reference' conflicts with the "
                                 f"reference: section, which sets it")
    study["reference"] = ref
    study["checks"] = _checks(raw.get("checks"), study, f"{path}: checks")
    return study


# ------------------------------------------------------------------------------ run plan

@dataclass
class Run:
    """One solver run: what to pass, where it writes, and (after execution) what came back."""
    kind: str                        # "run" or "reference"
    series: int                      # index into study["series"]
    level: Optional[int]             # level index; None for a per-series reference
    options: dict                    # merged options, key (no dash) -> value text
    output: str                      # HDF5 file, relative to ROOT when inside it
    reference: Optional[str] = None  # HDF5 file passed as -reference
    returncode: Optional[int] = None
    attrs: Optional[dict] = None     # /run attributes read back

    def describe(self, study):
        """Human-readable name, e.g. "series 'nu=0.5' level 2" or "reference of series 'a'"."""
        label = study["series"][self.series]["label"]
        where = f"series {label!r}" + ("" if self.level is None else f" level {self.level}")
        return where if self.kind == "run" else f"reference of {where}"


def plan_runs(study, outdir):
    """List the runs in execution order; each reference run comes before the runs using it."""
    out = display_path(outdir)
    ref = study["reference"]
    plan = []
    for i, s in enumerate(study["series"]):
        base = {**study["options"], **s["options"]}
        ref_file = None
        if ref is not None and ref["per"] == "series":
            ref_file = os.path.join(out, f"{s['stem']}_ref.h5")
            plan.append(Run("reference", i, None, {**base, **study["levels"][-1], **ref["options"]},
                            ref_file))
        for k, level in enumerate(study["levels"]):
            if ref is not None and ref["per"] == "level":
                ref_file = os.path.join(out, f"{s['stem']}_{k}_ref.h5")
                plan.append(Run("reference", i, k, {**base, **level, **ref["options"]}, ref_file))
            plan.append(Run("run", i, k, {**base, **level}, os.path.join(out, f"{s['stem']}_{k}.h5"),
                            reference=ref_file))
    return plan


def command(run, study, nprocs):
    """The mpiexec command line of `run` (to be executed in ROOT)."""
    cmd = ["mpiexec", "-n", str(nprocs), BIN]
    if study["options_file"] is not None:
        cmd += ["-options_file", study["options_file"]]
    for key, value in run.options.items():
        cmd += [f"-{key}", value]
    if run.reference is not None:
        cmd += ["-reference", run.reference]
    return cmd + ["-output", run.output]


# ------------------------------------------------------------------------------ execution

def execute(run, cmd, study):
    """Run `cmd` in ROOT, save its console output beside the HDF5 file, read /run back.

    Sets run.returncode and run.attrs. Raises StudyError, with the tail of the solver output, if
    the run wrote no file, and naming the file and attribute if /run lacks converged, the abscissa
    or a norm. A failed run that did write its file (converged = 0) is warned about on stderr and
    kept.
    """
    h5 = os.path.join(ROOT, run.output)
    if os.path.exists(h5):
        os.remove(h5)  # never read back a file left by an earlier study
    log = h5[:-3] + ".log"
    proc = run_mpi(cmd, log)
    run.returncode = proc.returncode
    if not os.path.exists(h5):
        raise StudyError(f"{run.describe(study)} exited with status {proc.returncode} and wrote no "
                         f"{run.output}; command:\n  {shlex.join(cmd)}\nlast lines of its output "
                         f"(all in {display_path(log)}):\n{tail(proc.output, LOG_TAIL_LINES)}")
    try:
        run.attrs = read_run(h5)
    except ValueError as exc:
        raise StudyError(str(exc)) from exc
    needed = ["converged"] + ([study["x"]] + study["norms"] if run.kind == "run" else [])
    for attr in needed:
        if attr not in run.attrs:
            role = {"converged": "to flag failed runs", study["x"]: "as abscissa"}.get(attr, "as a norm")
            raise StudyError(f"{run.output}: /run has no attribute '{attr}' (needed {role})")
    if not run_ok(run):
        print(f"WARNING: {run.describe(study)} FAILED: exit status {run.returncode}, converged = "
              f"{run.attrs['converged']} (reason {run.attrs.get('snes_reason', '?')}); "
              f"log {display_path(log)}", file=sys.stderr)


def run_ok(run):
    """True when the run exited 0 and wrote converged = 1."""
    return run.returncode == 0 and run.attrs["converged"] == 1


def execute_all(plan, study, nprocs, quiet):
    """Execute the plan in order, printing each command as it starts unless `quiet`."""
    for n, run in enumerate(plan, 1):
        cmd = command(run, study, nprocs)
        if not quiet:
            print(f"[{n}/{len(plan)}] {shlex.join(cmd)}", flush=True)
        execute(run, cmd, study)


def run_table(plan, study):
    """table[i][k]: the Run (not a reference run) of series i, level k."""
    table = [[None] * len(study["levels"]) for _ in study["series"]]
    for run in plan:
        if run.kind == "run":
            table[run.series][run.level] = run
    return table


# ------------------------------------------------------------------------------ rates

def analyse(study, table):
    """Abscissae, values, level rates and fitted rates of every (series, norm).

    Returns {"x": [list of x per series], (i, norm): {"e", "rates", "fit"}}; the fit uses the
    last fit_levels levels.
    """
    first = len(study["levels"]) - study["fit_levels"]
    res = {"x": []}
    for i, row in enumerate(table):
        x = [run.attrs[study["x"]] for run in row]
        res["x"].append(x)
        for norm in study["norms"]:
            e = [run.attrs[norm] for run in row]
            res[(i, norm)] = {"e": e, "rates": level_rates(x, e),
                              "fit": fitted_rate(x[first:], e[first:], first)}
    return res


# ------------------------------------------------------------------------------ checks

def evaluate_checks(study, plan, analysis):
    """Evaluate the implicit 'all runs converged' check and the study's checks.

    Returns [(passed, line)] with one line per check, starting with its description.
    """
    results = []
    failed = [f"{r.describe(study)} (exit {r.returncode}, converged = {r.attrs['converged']})"
              for r in plan if not run_ok(r)]
    results.append((not failed, f"converged: all {len(plan)} runs exit 0 with converged = 1"
                    + (f"; failed: {', '.join(failed)}" if failed else "")))
    tol = study["tolerance"]
    for n, c in enumerate(study["checks"], 1):
        details, ok = [], True
        if c["type"] == "rate":
            head = f"check {n} rate {', '.join(c['norms'])}: fitted >= predicted - {tol:g}"
            for norm in c["norms"]:
                for i, s in enumerate(study["series"]):
                    if norm not in s["predicted"]:
                        continue
                    p = s["predicted"][norm]
                    rate, note = analysis[(i, norm)]["fit"]
                    good = agrees(rate, p, tol)
                    ok &= good
                    details.append(f"{s['label']} {norm}: fitted {format_rate(rate, note)} "
                                   f"{'>=' if good else 'NOT >='} {p:g} - {tol:g}")
        else:
            head = (f"check {n} monotone {c['norm']} (floor_ratio {c['floor_ratio']:g}): "
                    f"decreases until a floor")
            for i, s in enumerate(study["series"]):
                good, detail = monotone_until_floor(analysis["x"][i], analysis[(i, c["norm"])]["e"],
                                                    c["floor_ratio"])
                ok &= good
                details.append(f"{s['label']}: {detail}")
        results.append((ok, f"{head}; " + "; ".join(details)))
    return results


# ------------------------------------------------------------------------------ reports

def write_csv(path, study, table, analysis):
    """One row per run; rate_<norm> is empty at level 0 and nan where it cannot be computed."""
    norms = study["norms"]
    rows = []
    for i, row in enumerate(table):
        for k, run in enumerate(row):
            a = run.attrs
            rates = [None if k == 0 else analysis[(i, n)]["rates"][k - 1][0] for n in norms]
            rows.append([study["series"][i]["label"], k, a[study["x"]]] + [a[n] for n in norms]
                        + [a.get("newton_its"), a.get("ksp_its"), a.get("time_solve"),
                           a["converged"], run.returncode] + rates + [os.path.basename(run.output)])
    write_csv_file(path, ["series", "level", study["x"]] + norms
                   + ["newton_its", "ksp_its", "time_solve", "converged", "exit_code"]
                   + [f"rate_{n}" for n in norms] + ["file"], rows)


def write_markdown(path, study, plan, table, analysis):
    """The Markdown report: set-up, failed runs, one table per series, the rate summary."""
    x, norms, nfit = study["x"], study["norms"], study["fit_levels"]
    out = [f"# Study {study['name']}", ""]
    if study["description"]:
        out += [study["description"], ""]
    out += [f"- abscissa: `{x}`; fit over the last {nfit} of {len(study['levels'])} levels; "
            f"agreement: fitted >= predicted - {study['tolerance']:g}",
            f"- options file: `{study['options_file']}`" if study["options_file"] else "- options file: -",
            f"- options of every run: {md_options(study['options'])}"]
    if study["reference"]:
        out.append(f"- reference runs (one per {study['reference']['per']}): "
                   f"{md_options(study['reference']['options'])}")
    out.append("")
    failed = [r for r in plan if not run_ok(r)]
    if failed:
        out += ["**WARNING: failed runs**", ""]
        out += [f"- {r.describe(study)}: exit status {r.returncode}, converged = "
                f"{r.attrs['converged']} ({r.attrs.get('snes_reason', '?')}), `{r.output}`"
                for r in failed]
        out.append("")
    for i, s in enumerate(study["series"]):
        out += [f"## Series {s['label']}", "", f"Options: {md_options(s['options'])}", ""]
        head = ["level", "level options", x]
        for n in norms:
            head += [n, f"rate {n}"]
        head += ["newton_its", "ksp_its", "converged"]
        out += [md_row(head), md_rule(len(head))]
        for k, run in enumerate(table[i]):
            cells = [str(k), md_options(study["levels"][k]), format_value(run.attrs[x])]
            for n in norms:
                a = analysis[(i, n)]
                cells += [format_value(a["e"][k]), "" if k == 0 else format_rate(*a["rates"][k - 1])]
            cells += [str(run.attrs.get("newton_its", "")), str(run.attrs.get("ksp_its", "")),
                      "yes" if run_ok(run) else f"**NO** (exit {run.returncode})"]
            out.append(md_row(cells))
        out.append("")
    out += ["## Summary", "",
            f"| series | norm | predicted | fitted (last {nfit} levels) | agrees |",
            "|---|---|---|---|---|"]
    for i, s in enumerate(study["series"]):
        for n in norms:
            rate, note = analysis[(i, n)]["fit"]
            p = s["predicted"].get(n)
            verdict = "-" if p is None else ("yes" if agrees(rate, p, study["tolerance"]) else "no")
            out.append(f"| {s['label']} | {n} | {'-' if p is None else f'{p:g}'} | "
                       f"{format_rate(rate, note)} | {verdict} |")
    out += ["", "nan: a rate needs finite, positive values at distinct x; the note names the "
            "offending level.", ""]
    out += [f"![{n}]({study['name']}_{n}.png)" for n in norms]
    write_lines(path, out)


def write_plot(path, study, norm, analysis):
    """Log-log plot of `norm` against the abscissa for all series, with predicted slopes."""
    markers = "os^vDPX*<>"
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    plotted = False
    for i, s in enumerate(study["series"]):
        x, e = analysis["x"][i], analysis[(i, norm)]["e"]
        pts = [(a, b) for a, b in zip(x, e) if not invalid(a) and not invalid(b)]
        if not pts:
            continue
        plotted = True
        rate, note = analysis[(i, norm)]["fit"]
        px, pe = zip(*pts)
        line, = ax.plot(px, pe, marker=markers[i % len(markers)], label=
                        f"{s['label']} (fitted {'nan' if note else f'{rate:.2f}'})")
        p = s["predicted"].get(norm)
        if p is not None and not invalid(x[-1]) and not invalid(e[-1]):
            xs = np.array([min(px), max(px)])
            ax.plot(xs, e[-1] * (xs / x[-1]) ** p, "--", color=line.get_color(),
                    label=f"slope {p:g} ({s['label']})")
    ax.set_xscale("log")
    ax.set_yscale("log")
    if plotted:
        ax.legend(fontsize="small")
    else:
        no_values_note(ax, norm)
    ax.grid(True, which="both", alpha=0.3)
    ax.set_xlabel(study["x"])
    ax.set_ylabel(norm)
    ax.set_title(f"{study['name']}: {norm}")
    save_png(fig, path, 120)


# ------------------------------------------------------------------------------ main

def main(argv=None):
    """Command-line entry point; returns the exit status (0 ok, 1 failed check, 2 error)."""
    ap = argparse.ArgumentParser(description=__doc__,  # -h shows the study file format
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", metavar="STUDY.yaml", help="the study file")
    ap.add_argument("--outdir", metavar="DIR",
                    help="output directory, created if needed (default: output/studies/<name>/ in the "
                         "repository)")
    ap.add_argument("--np", type=int, metavar="N", help="MPI ranks per run (overrides np: of the study)")
    ap.add_argument("--dry-run", action="store_true", help="print the commands, run nothing")
    ap.add_argument("--check", action="store_true",
                    help="evaluate the study's checks (and that every run converged); exit 1 on a failure")
    ap.add_argument("--quiet", action="store_true", help="do not print the commands as they start")
    args = ap.parse_args(argv)
    if args.dry_run and args.check:
        ap.error("--check needs the runs; it cannot be combined with --dry-run")
    if args.np is not None and args.np < 1:
        ap.error(f"--np must be >= 1, got {args.np}")

    try:
        study = load_study(args.study)
        outdir = os.path.abspath(args.outdir or os.path.join(ROOT, "output", "studies", study["name"]))
        nprocs = args.np or study["np"]
        plan = plan_runs(study, outdir)
        if args.dry_run:
            print(f"# {len(plan)} runs, in {ROOT}")
            for run in plan:
                print(shlex.join(command(run, study, nprocs)))
            return 0
        os.makedirs(outdir, exist_ok=True)
        if not args.quiet:
            print(f"study {study['name']}: {len(plan)} runs in {ROOT}, output in {display_path(outdir)}")
        execute_all(plan, study, nprocs, args.quiet)
        table = run_table(plan, study)
    except StudyError as exc:
        print(f"study.py: error: {exc}", file=sys.stderr)
        return 2

    analysis = analyse(study, table)
    base = os.path.join(outdir, study["name"])
    write_csv(base + ".csv", study, table, analysis)
    write_markdown(base + ".md", study, plan, table, analysis)
    for norm in study["norms"]:
        write_plot(f"{base}_{norm}.png", study, norm, analysis)
    failed = [r for r in plan if not run_ok(r)]
    if failed:
        print(f"WARNING: {len(failed)} of {len(plan)} runs failed (see the converged column)",
              file=sys.stderr)
    if not args.quiet:
        print(f"wrote {display_path(base)}.csv, .md and {len(study['norms'])} plots")
    if not args.check:
        return 0
    results = evaluate_checks(study, plan, analysis)
    for ok, line in results:
        print(("PASS " if ok else "FAIL ") + line)
    bad = [line for ok, line in results if not ok]
    if bad:
        print(f"study.py: {len(bad)} of {len(results)} checks failed:\n"
              + "\n".join(f"  - {line}" for line in bad), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
