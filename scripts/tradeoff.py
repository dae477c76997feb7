#!/usr/bin/python3
"""Speed-versus-accuracy trade-off study of bin/signorini: which method, eps rule, linear solver and
mesh reach a given error in the least time.

Usage: tradeoff.py STUDY.yaml [--outdir DIR] [--np N] [--dry-run] [--quiet]

The study file names problems (a scene with its mesh levels and the error norms to judge) and three
factors: contact methods, eps rules (penalty methods only) and linear solvers. Every problem runs
the full product grid, level x method x eps rule x solver, except the combinations the study file
skips; a method that does not use eps (SNESVI) runs once per (level, solver), not once per eps rule.
Each run is, in the repository root,

    mpiexec -n NP bin/signorini [-options_file PROBLEM_FILE] [-options_file SOLVER_FILE]
        <problem options> <level options> <solver options> <method options> <eps rule options>
        [-reference DIR/<problem>_ref.h5] -output DIR/<problem>_<level>_<method>[_<eps>]_<solver>.h5

(later options win). A problem with a `reference:` section first gets one reference run, before any
other run of the study, written to DIR/<problem>_ref.h5 and passed as -reference to all its runs; a
reference run that fails stops the study. The /run attributes of every output file are read back
with read_runs.read_run, and DIR (default output/tradeoff/<name>/ in the repository) receives:

    <name>.csv             one row per run: problem, level, level_label, method, eps_rule, solver,
                           np, h, eps, n_dofs, every error norm found (error_*, reference_error_*,
                           penetration_*), time_setup, time_solve, time_total, cost, newton_its,
                           ksp_its, peak_memory_mb, converged, snes_reason, exit_code, status,
                           wall_time (seconds of the whole mpiexec, measured by this driver),
                           notes, file
    <name>.md              the set-up, the skipped combinations and the failed runs, the full table
                           of every problem, the Pareto fronts, the recommendation table
    <name>_<problem>_<norm>.png   error (log) against cost (log): every run a marker (colour: method
                           and eps rule; shape: solver), failed runs as grey crosses, the Pareto front
                           joined by a black line, its points labelled with their mesh level
    <problem>_*.h5, .xdmf, .log   solver output and console log of every run

The recommendation table is also printed on stdout (Markdown), followed by one sentence per row.

Analysis. The cost of a run is its `cost` (default time_total, the solver's own wall time from
start-up to the end of the error norms; the time spent in mpiexec start-up is not included). Only
*usable* runs enter the analysis of a norm: status ok (exit 0 and converged = 1) and a finite cost
and error. A run dominates another when it is no slower and no less accurate and strictly better in
one of the two, where errors within the relative tolerance error_rtol count as equal: the same
discrete solution computed by two linear solvers differs by round-off (1e-10 here), and a slower
solver must not reach the front by it. The Pareto front is the set of usable runs that no usable run
dominates (runs with equal cost and error are all kept), sorted by cost. The recommendation for
(problem, norm, target) is the usable run with error <= target of least cost; a tie in cost goes to
the smaller error, then to the run planned first. It lies on the Pareto front (up to error_rtol).
"none reaches it" when no usable run reaches the target. Failed runs are listed (CSV, tables,
plots) but never enter a front or a recommendation.

Missing attributes. An attribute the analysis expects (h, eps, n_dofs, the times, newton_its,
ksp_its, peak_memory_mb, converged and the problem's norms) that an output file lacks becomes nan,
is named in the row's `notes` and counted in a note of the report; the study goes on. A run that
exits without writing its file (e.g. an option combination the solver refuses) becomes a row with
status "no output" and the last line of its log in `notes`; a run that exceeds `timeout` is killed
and gets status "timeout".

Study file (YAML). Keys marked * are required; any other key is an error, named with its path.

    name: tradeoff             # * used in file names: letters, digits, '.', '_', '-'
    description: text          #   copied into the Markdown report
    np: 1                      #   default MPI ranks per run (a problem's np overrides; --np both)
    timeout: 600               #   seconds per run before it is killed (default: no limit)
    cost: time_total           #   /run attribute(s) used as cost: a name, or a list of names that
                               #   are summed, e.g. [time_setup, time_solve] (default time_total)
    error_rtol: 1e-6           #   errors within this relative tolerance count as equal in the
                               #   Pareto fronts (default 1e-6; see Analysis)
    norms: [error_h1]          #   default norms of the problems (/run attributes, lower is better)
    targets:                   # * target errors of each norm, a non-empty list of numbers > 0
      error_h1: [1e-1, 3e-2]   #   (strings such as 1e-1, which YAML 1.1 reads as text, are accepted)
    problems:                  # * non-empty list
      - name: mms2d            # * unique, file-name safe
        description: text
        options_file: options/mms.yaml   # relative to the repository root
        options: {dm_plex_dim: 2}        # option key without the dash: string, number or boolean
        np: 1
        cost: time_total       #   overrides the study's cost
        norms: [error_h1]      #   overrides the study's norms (one of the two must be given)
        targets: {error_h1: [1e-2]}      # overrides the study's targets of these norms
        levels:                # * at least one, coarsest first: a list of option mappings
          - {dm_plex_box_faces: "16,16"}
        # or {key: dm_plex_box_faces, values: ["16,16", "32,32"], labels: ["16x16", "32x32"]}
        # labels (optional) name the levels in the tables; by default "16x16" for
        # dm_plex_box_faces 16,16, else "key=value ..."
        reference:             #   optional: one reference run of the problem, before all runs
          options: {dm_refine: 5, contact_method: vi}   # * added to the problem's options
          options_file: F      #   optional, after the problem's options file
          solver: mumps        #   optional: also the options of that solver
    methods:                   # * non-empty list
      - name: penalty_gauss    # * unique, file-name safe
        text: penalty gauss    #   words used in the recommendation sentences (default: name)
        options: {contact_method: penalty, penalty_quadrature: gauss}
        uses_eps: true         #   false: run once per (level, solver), the eps rule is "-"
    eps_rules:                 #   needed (non-empty) when a method uses eps; same keys as methods
      - {name: h, text: "eps = h", options: {penalty_eps_power: 1}}          # except uses_eps
    solvers:                   # * non-empty list: name, text, options_file, options
      - {name: mumps, options_file: options/solvers/mumps.yaml}
    skip:                      #   combinations not run, listed in the report with their reason
      - {method: vi, solver: gamg, reason: "the solver refuses it"}
        # selectors: any of problem, method, eps_rule, solver (at least one), each a name or a
        # list of names; reason * ; a run is skipped when every given selector matches it

The options `output` and `reference` are set by the driver and may not appear in any options.

Exit status: 0 every planned run wrote its output file (runs with converged = 0 are results, shown
as failed); 1 some run wrote no file or timed out (the reports are still written); 2 an error that
stops the study (bad study file, a failed reference run, an unreadable output file).
"""
import argparse
import math
import os
import shlex
import sys
import time
from dataclasses import dataclass, field
from typing import Optional

SCRIPTS = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, SCRIPTS)
from signorini.figures import no_values_note, plt, save_png  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402  (after figures, which selects the Agg backend)
from signorini.formatting import finite, fmt_mem, fmt_time, fmt_val, sci, short  # noqa: E402
from signorini.mpirun import LOG_TAIL_LINES, MPI_ENV, error_line, run_mpi, tail  # noqa: E402,F401
from signorini.paths import BIN, ROOT, display_path  # noqa: E402
from signorini.pareto import (ERROR_RTOL, dominates, pareto_front, recommend,  # noqa: E402,F401
                              same_error, usable)
from signorini.report import md_options, md_row, md_rule, write_csv as write_csv_file, write_lines  # noqa: E402
from signorini.runs import read_run  # noqa: E402
from signorini.studyfile import (NAME_RE, StudyError, check_keys, integer, name_list,  # noqa: E402,F401
                                 option_value, options, options_file, positive, read_yaml,
                                 safe_label, safe_name, string)

TOP_KEYS = ("name", "description", "np", "timeout", "cost", "error_rtol", "norms", "targets",
            "problems", "methods", "eps_rules", "solvers", "skip")
TOP_REQUIRED = ("name", "targets", "problems", "methods", "solvers")
PROBLEM_KEYS = ("name", "description", "options_file", "options", "np", "cost", "norms", "targets",
                "levels", "reference")
FACTOR_KEYS = {"methods": ("name", "text", "options", "uses_eps"),
               "eps_rules": ("name", "text", "options"),
               "solvers": ("name", "text", "options_file", "options")}
SKIP_SELECTORS = {"problem": "problems", "method": "methods", "eps_rule": "eps_rules",
                  "solver": "solvers"}

# Error columns of the CSV, in this order when present (plus any other norm a problem names).
_BASE_ERRORS = ["error_h1", "error_h1_semi", "error_l2", "error_energy", "error_pressure_l2",
                "error_pressure_weighted", "error_pressure_dual"]
NORM_COLUMNS = (_BASE_ERRORS + ["reference_" + n for n in _BASE_ERRORS]
                + ["penetration_l2", "penetration_max"])
# Attributes every run is expected to have; a missing one is nan with a note.
EXPECTED = ["h", "eps", "n_dofs", "time_setup", "time_solve", "time_total", "newton_its",
            "ksp_its", "peak_memory_mb", "converged"]
NO_EPS = "-"  # eps_rule of a method that does not use eps
RESERVED = ("output", "reference")  # options set by the driver
NAN = float("nan")


# ------------------------------------------------------------------------------ study file

def _options(value, where):
    """An options mapping -> {key: command-line text}; keys without the dash; no output, reference."""
    return options(value, where, RESERVED, name_key=True)


def _cost(value, where):
    """`cost`: an attribute name or a non-empty list of them -> list of names."""
    if isinstance(value, str):
        return [value]
    return name_list(value, where)


def _targets(value, where):
    """{norm: [target, ...]} with positive targets, sorted from the loosest (largest) down."""
    if not isinstance(value, dict) or not value:
        raise StudyError(f"{where}: expected a mapping norm: [target errors]")
    out = {}
    for norm, ts in value.items():
        if not isinstance(norm, str):
            raise StudyError(f"{where}: norm {norm!r} is not a string")
        if not isinstance(ts, list) or not ts:
            raise StudyError(f"{where}.{norm}: expected a non-empty list of target errors")
        vals = [positive(t, f"{where}.{norm}[{i}]") for i, t in enumerate(ts)]
        out[norm] = sorted(set(vals), reverse=True)
    return out


def level_label(opts):
    """Default label of a level: '16x16' for dm_plex_box_faces 16,16, else 'key=value ...'."""
    if list(opts) == ["dm_plex_box_faces"]:
        return opts["dm_plex_box_faces"].replace(",", "x")
    return " ".join(f"{k}={v}" for k, v in opts.items()) or "default"


def _levels(value, where):
    """Levels -> list of {"options", "label"}."""
    labels = None
    if isinstance(value, dict):
        check_keys(value, ("key", "values", "labels"), ("key", "values"), where)
        if not isinstance(value["key"], str):
            raise StudyError(f"{where}.key: expected an option name")
        if not isinstance(value["values"], list) or not value["values"]:
            raise StudyError(f"{where}.values: expected a non-empty list")
        labels = value.get("labels")
        if labels is not None and (not isinstance(labels, list)
                                   or len(labels) != len(value["values"])):
            raise StudyError(f"{where}.labels: expected a list of {len(value['values'])} labels "
                             f"(one per value)")
        value = [{value["key"]: v} for v in value["values"]]
    if not isinstance(value, list) or not value:
        raise StudyError(f"{where}: expected a non-empty list of option mappings or "
                         f"{{key, values, labels}}")
    out = []
    for k, lev in enumerate(value):
        opts = _options(lev, f"{where}[{k}]")
        label = level_label(opts) if labels is None else string(labels[k], f"{where}.labels[{k}]")
        out.append({"options": opts, "label": label})
    if len({lev["label"] for lev in out}) != len(out):
        raise StudyError(f"{where}: two levels have the same label; give distinct labels")
    return out


def _factor(value, kind, where):
    """A factor list (methods, eps_rules, solvers) -> list of dicts with all keys filled in."""
    if not isinstance(value, list) or not value:
        raise StudyError(f"{where}: expected a non-empty list")
    out, names = [], set()
    for i, item in enumerate(value):
        w = f"{where}[{i}]"
        check_keys(item, FACTOR_KEYS[kind], ("name",), w)
        name = safe_name(item["name"], f"{w}.name")
        if name in names:
            raise StudyError(f"{w}.name: {name!r} appears twice in {kind}")
        names.add(name)
        entry = {"name": name, "text": string(item.get("text", name), f"{w}.text"),
                 "options": _options(item.get("options"), f"{w}.options"),
                 "options_file": options_file(item.get("options_file"), f"{w}.options_file")}
        if kind == "methods":
            uses = item.get("uses_eps", True)
            if not isinstance(uses, bool):
                raise StudyError(f"{w}.uses_eps: expected true or false, got {uses!r}")
            entry["uses_eps"] = uses
        out.append(entry)
    return out


def _problem(value, i, study, where):
    """One problem -> normalized dict."""
    w = f"{where}[{i}]"
    check_keys(value, PROBLEM_KEYS, ("name", "levels"), w)
    p = {"name": safe_name(value["name"], f"{w}.name"),
         "description": string(value.get("description", ""), f"{w}.description"),
         "options_file": options_file(value.get("options_file"), f"{w}.options_file"),
         "options": _options(value.get("options"), f"{w}.options"),
         "np": integer(value.get("np", study["np"]), f"{w}.np", 1),
         "cost": _cost(value["cost"], f"{w}.cost") if "cost" in value else study["cost"],
         "levels": _levels(value["levels"], f"{w}.levels")}
    if "norms" in value:
        p["norms"] = name_list(value["norms"], f"{w}.norms")
    elif study["norms"] is not None:
        p["norms"] = study["norms"]
    else:
        raise StudyError(f"{w}: missing key 'norms' (and the study has no default norms)")
    targets = dict(study["targets"])
    if "targets" in value:
        targets.update(_targets(value["targets"], f"{w}.targets"))
    for norm in p["norms"]:
        if norm not in targets:
            raise StudyError(f"{w}.norms: norm '{norm}' has no targets (add it to targets:)")
    p["targets"] = {n: targets[n] for n in p["norms"]}
    ref = value.get("reference")
    if ref is not None:
        rw = f"{w}.reference"
        check_keys(ref, ("options", "options_file", "solver"), ("options",), rw)
        solver = ref.get("solver")
        if solver is not None and solver not in [s["name"] for s in study["solvers"]]:
            raise StudyError(f"{rw}.solver: {solver!r} is not one of the solvers")
        ref = {"options": _options(ref["options"], f"{rw}.options"),
               "options_file": options_file(ref.get("options_file"), f"{rw}.options_file"),
               "solver": solver}
    p["reference"] = ref
    return p


def _skip(value, study, where):
    """The skip list -> list of {selector: set of names, "reason": text}."""
    if value is None:
        return []
    if not isinstance(value, list):
        raise StudyError(f"{where}: expected a list")
    out = []
    for i, item in enumerate(value):
        w = f"{where}[{i}]"
        check_keys(item, tuple(SKIP_SELECTORS) + ("reason",), ("reason",), w)
        entry = {"reason": string(item["reason"], f"{w}.reason")}
        for sel, kind in SKIP_SELECTORS.items():
            if sel not in item:
                continue
            names = item[sel] if isinstance(item[sel], list) else [item[sel]]
            known = [x["name"] for x in study[kind]]
            for n in names:
                if n not in known:
                    raise StudyError(f"{w}.{sel}: {n!r} is not one of the {kind} "
                                     f"({', '.join(known) or 'none'})")
            entry[sel] = set(names)
        if len(entry) == 1:
            raise StudyError(f"{w}: give at least one of {', '.join(SKIP_SELECTORS)}")
        out.append(entry)
    return out


def load_study(path):
    """Read and validate a trade-off study file; return it normalized (see the docstring).

    Raises StudyError naming the file and the key at fault.
    """
    raw = read_yaml(path)
    check_keys(raw, TOP_KEYS, TOP_REQUIRED, path)
    w = f"{path}:"
    study = {"name": safe_name(raw["name"], f"{w} name"),
             "description": string(raw.get("description", ""), f"{w} description"),
             "np": integer(raw.get("np", 1), f"{w} np", 1),
             "timeout": (None if raw.get("timeout") is None
                         else positive(raw["timeout"], f"{w} timeout")),
             "cost": _cost(raw.get("cost", "time_total"), f"{w} cost"),
             "error_rtol": positive(raw.get("error_rtol", ERROR_RTOL), f"{w} error_rtol"),
             "norms": name_list(raw["norms"], f"{w} norms") if "norms" in raw else None,
             "targets": _targets(raw["targets"], f"{w} targets")}
    for kind in ("methods", "solvers"):
        study[kind] = _factor(raw[kind], kind, f"{w} {kind}")
    if any(m["uses_eps"] for m in study["methods"]):
        if "eps_rules" not in raw:
            raise StudyError(f"{w} eps_rules: missing, but method(s) "
                             f"{', '.join(m['name'] for m in study['methods'] if m['uses_eps'])} "
                             f"use eps (set uses_eps: false for a method without eps)")
        study["eps_rules"] = _factor(raw["eps_rules"], "eps_rules", f"{w} eps_rules")
    else:
        study["eps_rules"] = (_factor(raw["eps_rules"], "eps_rules", f"{w} eps_rules")
                              if raw.get("eps_rules") is not None else [])
    probs = raw["problems"]
    if not isinstance(probs, list) or not probs:
        raise StudyError(f"{w} problems: expected a non-empty list")
    study["problems"] = []
    for i, p in enumerate(probs):
        prob = _problem(p, i, study, f"{w} problems")
        if prob["name"] in [q["name"] for q in study["problems"]]:
            raise StudyError(f"{w} problems[{i}].name: {prob['name']!r} appears twice")
        study["problems"].append(prob)
    study["skip"] = _skip(raw.get("skip"), study, f"{w} skip")
    return study


# ------------------------------------------------------------------------------ run plan

@dataclass
class Run:
    """One solver run; `row` is filled in after execution (see make_row)."""
    kind: str                      # "run" or "reference"
    problem: dict
    output: str                    # HDF5 file, relative to ROOT when inside it
    args: list                     # solver arguments (without mpiexec, binary and -output)
    np: int
    level: Optional[int] = None
    method: Optional[dict] = None
    eps_rule: Optional[dict] = None
    solver: Optional[dict] = None
    index: int = 0                 # position in the plan (tie-break of the recommendations)
    returncode: Optional[int] = None
    attrs: Optional[dict] = None
    wall: float = NAN
    status: str = "not run"        # ok, failed, no output, timeout
    notes: list = field(default_factory=list)

    def describe(self):
        p = self.problem["name"]
        if self.kind == "reference":
            return f"reference run of {p}"
        eps = "" if self.eps_rule is None else f", eps {self.eps_rule['name']}"
        return (f"{p} level {self.problem['levels'][self.level]['label']}, "
                f"{self.method['name']}{eps}, {self.solver['name']}")


def _args(files, option_maps):
    """Solver arguments: -options_file for every file, then every option (later wins)."""
    out = []
    for f in files:
        if f is not None:
            out += ["-options_file", f]
    for opts in option_maps:
        for k, v in opts.items():
            out += [f"-{k}", v]
    return out


def skip_reason(study, problem, method, eps_rule, solver):
    """The reason of the first skip entry matching this combination, or None."""
    names = {"problem": problem["name"], "method": method["name"],
             "eps_rule": None if eps_rule is None else eps_rule["name"], "solver": solver["name"]}
    for entry in study["skip"]:
        if all(names[sel] in entry[sel] for sel in SKIP_SELECTORS if sel in entry):
            return entry["reason"]
    return None


def plan_runs(study, outdir, nprocs=None):
    """(plan, skipped): all reference runs first, then every problem's grid; skipped combinations
    as (problem, method, eps_rule or None, solver, reason), once per combination (not per level)."""
    out = display_path(outdir)
    solvers = {s["name"]: s for s in study["solvers"]}
    refs, runs, skipped = [], [], []
    for p in study["problems"]:
        np_ = nprocs or p["np"]
        ref_file = None
        if p["reference"] is not None:
            r = p["reference"]
            s = solvers.get(r["solver"])
            ref_file = os.path.join(out, f"{p['name']}_ref.h5")
            refs.append(Run("reference", p, ref_file, np=np_, solver=s, args=_args(
                [p["options_file"], r["options_file"], s and s["options_file"]],
                [p["options"], s["options"] if s else {}, r["options"]])))
        for m in study["methods"]:
            for e in (study["eps_rules"] if m["uses_eps"] else [None]):
                for s in study["solvers"]:
                    why = skip_reason(study, p, m, e, s)
                    if why is not None:
                        skipped.append((p, m, e, s, why))
        for k, lev in enumerate(p["levels"]):
            for m in study["methods"]:
                for e in (study["eps_rules"] if m["uses_eps"] else [None]):
                    for s in study["solvers"]:
                        if skip_reason(study, p, m, e, s) is not None:
                            continue
                        stem = "_".join([p["name"], str(k), m["name"]]
                                        + ([e["name"]] if e else []) + [s["name"]])
                        args = _args([p["options_file"], s["options_file"]],
                                     [p["options"], lev["options"], s["options"], m["options"],
                                      e["options"] if e else {}])
                        if ref_file:
                            args += ["-reference", ref_file]
                        runs.append(Run("run", p, os.path.join(out, safe_label(stem) + ".h5"),
                                        args, np_, k, m, e, s))
    plan = refs + runs
    for n, run in enumerate(plan):
        run.index = n
    return plan, skipped


def command(run):
    """The mpiexec command line of `run` (to be executed in ROOT)."""
    return ["mpiexec", "-n", str(run.np), BIN] + run.args + ["-output", run.output]


# ------------------------------------------------------------------------------ execution

def execute(run, timeout):
    """Run it in ROOT; save the console log beside the HDF5 file; read /run back.

    Sets returncode, wall, status, attrs and notes. A run that writes no file (or times out) is
    recorded, not raised; an output file that cannot be read raises StudyError.
    """
    cmd = command(run)
    h5 = os.path.join(ROOT, run.output)
    for stale in (h5, h5[:-3] + ".xdmf"):
        if os.path.exists(stale):
            os.remove(stale)  # never read back a file left by an earlier study
    proc = run_mpi(cmd, h5[:-3] + ".log", timeout)
    run.wall = proc.wall
    run.returncode = proc.returncode
    if proc.timed_out:
        run.status = "timeout"
        run.notes.append(f"killed after the timeout of {timeout:g} s")
        return
    if not os.path.exists(h5):
        run.status = "no output"
        run.notes.append(f"exit {proc.returncode}, no file: {error_line(proc.output)}")
        if run.kind == "reference":
            raise StudyError(f"{run.describe()} exited with status {proc.returncode} and wrote no "
                             f"{run.output}; command:\n  {shlex.join(cmd)}\nlast lines of its "
                             f"output:\n{tail(proc.output, LOG_TAIL_LINES)}")
        return
    try:
        run.attrs = read_run(h5)
    except ValueError as exc:
        raise StudyError(str(exc)) from exc
    conv = run.attrs.get("converged")
    run.status = "ok" if proc.returncode == 0 and conv == 1 else "failed"
    if run.status == "failed":
        run.notes.append(f"exit {proc.returncode}, converged = {conv}, "
                         f"{run.attrs.get('snes_reason', '?')} after "
                         f"{run.attrs.get('newton_its', '?')} Newton steps")
        if run.kind == "reference":
            raise StudyError(f"{run.describe()} failed ({'; '.join(run.notes)}): the runs of "
                             f"{run.problem['name']} cannot be measured against it; log "
                             f"{display_path(h5[:-3] + '.log')}")


def execute_all(plan, timeout, quiet):
    """Execute the plan in order, printing each command (unless quiet) and each failure."""
    for n, run in enumerate(plan, 1):
        if not quiet:
            print(f"[{n}/{len(plan)}] {shlex.join(command(run))}", flush=True)
        execute(run, timeout)
        if run.status != "ok":
            print(f"WARNING: {run.describe()}: {run.status.upper()}: {'; '.join(run.notes)} "
                  f"(log {display_path(os.path.join(ROOT, run.output))[:-3]}.log)",
                  file=sys.stderr, flush=True)


# ------------------------------------------------------------------------------ rows

def _num(v):
    """A finite-or-nan float from an attribute value (None and non-numbers -> nan)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return NAN
    return float(v)


def make_row(run):
    """The analysed record of an executed run: plain dict (see the CSV columns)."""
    p = run.problem
    a = run.attrs or {}
    row = {"problem": p["name"], "level": run.level, "level_label": p["levels"][run.level]["label"],
           "method": run.method["name"], "method_text": run.method["text"],
           "eps_rule": run.eps_rule["name"] if run.eps_rule else NO_EPS,
           "eps_text": run.eps_rule["text"] if run.eps_rule else "",
           "solver": run.solver["name"], "solver_text": run.solver["text"], "np": run.np,
           "status": run.status, "ok": run.status == "ok", "exit_code": run.returncode,
           "snes_reason": a.get("snes_reason", ""), "wall_time": run.wall,
           "file": os.path.basename(run.output), "index": run.index, "notes": list(run.notes),
           "run_notes": list(run.notes), "has_output": run.attrs is not None}
    missing = []
    for key in EXPECTED + [n for n in NORM_COLUMNS if n in a] + p["norms"]:
        if key in a:
            row[key] = a[key] if key == "converged" else _num(a[key])
        else:
            row[key] = NAN
            if run.attrs is not None and key not in missing:
                missing.append(key)
    cost = [row.get(k, _num(a.get(k))) for k in p["cost"]]
    for k in p["cost"]:
        if k not in a and run.attrs is not None and k not in missing:
            missing.append(k)
    row["cost"] = math.fsum(cost) if all(finite(c) for c in cost) else NAN
    if missing:
        row["notes"].append("missing: " + ", ".join(missing))  # CSV notes; run_notes: why it failed
    row["missing"] = missing
    return row


# ------------------------------------------------------------------------------ analysis

def recommendations(study, rows):
    """[(problem, norm, target, row or None)] for every problem, norm and target."""
    out = []
    for p in study["problems"]:
        prow = [r for r in rows if r["problem"] == p["name"]]
        for norm in p["norms"]:
            for t in p["targets"][norm]:
                out.append((p, norm, t, recommend(prow, norm, t)))
    return out


# ------------------------------------------------------------------------------ formatting

def cost_name(problem):
    return " + ".join(problem["cost"])


def run_text(row):
    """'penalty gauss, eps = h, mumps' (no eps part for a method without eps)."""
    parts = [row["method_text"]] + ([row["eps_text"]] if row["eps_text"] else []) + [row["solver_text"]]
    return ", ".join(parts)


def sentence(problem, norm, target, row):
    """One-line recommendation."""
    head = f"For {norm} <= {short(target)} on {problem['name']}"
    if row is None:
        return f"{head}: none reaches it."
    mem = "memory n/a" if not finite(row.get("peak_memory_mb")) else f"{row['peak_memory_mb']:.0f} MB"
    return (f"{head} use {run_text(row)} on {row['level_label']}: {fmt_time(row['cost'])} s, {mem} "
            f"(error {sci(row[norm])})")


def recommendation_table(recs):
    """Markdown table of the recommendations."""
    out = ["| problem | norm | target | method | eps rule | solver | level | cost [s] | memory [MB] "
           "| error |", "|---|---|---|---|---|---|---|---|---|---|"]
    for p, norm, t, r in recs:
        if r is None:
            out.append(f"| {p['name']} | {norm} | {short(t)} | none reaches it | | | | | | |")
        else:
            out.append(f"| {p['name']} | {norm} | {short(t)} | {r['method']} | {r['eps_rule']} | "
                       f"{r['solver']} | {r['level_label']} | {fmt_time(r['cost'])} | "
                       f"{fmt_mem(r['peak_memory_mb'])} | {sci(r[norm])} |")
    return out


# ------------------------------------------------------------------------------ reports

def csv_columns(study, rows):
    norms = [n for n in NORM_COLUMNS if any(n in r for r in rows)]
    extra = [n for p in study["problems"] for n in p["norms"] if n not in norms]
    norms += list(dict.fromkeys(extra))
    return (["problem", "level", "level_label", "method", "eps_rule", "solver", "np", "h", "eps",
             "n_dofs"] + norms + ["time_setup", "time_solve", "time_total", "cost", "newton_its",
                                  "ksp_its", "peak_memory_mb", "converged", "snes_reason",
                                  "exit_code", "status", "wall_time", "notes", "file"])


def write_csv(path, study, rows):
    cols = csv_columns(study, rows)
    cells = []
    for r in rows:
        cells.append([])
        for c in cols:
            v = r.get(c)
            if c in ("n_dofs", "newton_its", "ksp_its") and finite(v):
                v = int(v)
            cells[-1].append(v)
    write_csv_file(path, cols, cells, list_sep="; ")


def write_markdown(path, study, plan, skipped, rows, recs, elapsed):
    name = study["name"]
    out = [f"# Trade-off study {name}", ""]
    if study["description"]:
        out += [study["description"].strip(), ""]
    n_ok = sum(r["ok"] for r in rows)
    out += [f"- {len(rows)} runs ({n_ok} converged, {len(rows) - n_ok} failed) and "
            f"{sum(r.kind == 'reference' for r in plan)} reference run(s); "
            f"{len(skipped)} combination(s) skipped (on every level of their problem); "
            f"wall time of the study {elapsed:.0f} s",
            "- a run is *usable* for a norm when it converged and its cost and error are finite; "
            "only usable runs enter the Pareto fronts and the recommendations",
            "- cost: " + "; ".join(f"{p['name']}: `{cost_name(p)}`" for p in study["problems"])
            + " (seconds measured by the solver; the MPI start-up is not included)",
            "- methods: " + "; ".join(f"{m['name']} {md_options(m['options'])}"
                                      + ("" if m["uses_eps"] else " (no eps)")
                                      for m in study["methods"]),
            "- eps rules (penalty only): " + ("; ".join(f"{e['name']} {md_options(e['options'])}"
                                                          for e in study["eps_rules"]) or "-"),
            "- solvers: " + "; ".join(f"{s['name']} {md_options(files=[s['options_file']], opts=s['options'])}"
                                      for s in study["solvers"]), ""]
    if skipped:
        out += ["## Skipped combinations", "", "| problem | method | eps rule | solver | reason |",
                "|---|---|---|---|---|"]
        out += [f"| {p['name']} | {m['name']} | {e['name'] if e else NO_EPS} | {s['name']} | {why} |"
                for p, m, e, s, why in skipped]
        out.append("")
    failed = [r for r in rows if not r["ok"]]
    if failed:
        out += ["## Failed runs (excluded from the fronts and recommendations)", ""]
        out += [f"- {r['problem']} {r['level_label']}, {r['method']}, eps {r['eps_rule']}, "
                f"{r['solver']}: **{r['status']}** ({'; '.join(r['run_notes'])}), `{r['file']}`"
                for r in failed]
        out.append("")
    miss = {}
    for r in rows:
        for k in r["missing"]:
            miss[k] = miss.get(k, 0) + 1
    if miss:
        out += ["**Note: missing attributes** (nan in the tables): "
                + ", ".join(f"`{k}` in {n} of the {sum(r['has_output'] for r in rows)} output files"
                           for k, n in miss.items()), ""]
    for p in study["problems"]:
        prow = [r for r in rows if r["problem"] == p["name"]]
        out += [f"## Problem {p['name']}", ""]
        if p["description"]:
            out += [p["description"].strip(), ""]
        out += [f"Options: {md_options(files=[p['options_file']], opts=p['options'])}; {p['np']} rank(s); "
                f"levels: " + ", ".join(f"{lev['label']} ({md_options(lev['options'])})"
                                        for lev in p["levels"])]
        if p["reference"]:
            ref = p["reference"]
            out[-1] += (f"; reference run: {md_options(files=[ref['options_file']], opts=ref['options'])}"
                        + (f" with {ref['solver']}" if ref["solver"] else ""))
        out.append("")
        head = (["level", "method", "eps rule", "solver", "h", "eps", "n_dofs"] + p["norms"]
                + ["time_setup", "time_solve", "time_total", "cost", "newton", "ksp", "memory [MB]",
                   "status"])
        out += [md_row(head), md_rule(len(head))]
        for r in prow:
            cells = ([r["level_label"], r["method"], r["eps_rule"], r["solver"], fmt_val(r["h"]),
                      fmt_val(r["eps"]),
                      fmt_val(int(r["n_dofs"]) if finite(r["n_dofs"]) else r["n_dofs"])]
                     + [fmt_val(r[n]) for n in p["norms"]]
                     + [fmt_time(r[k]) for k in ("time_setup", "time_solve", "time_total", "cost")]
                     + [fmt_val(int(r[k]) if finite(r[k]) else r[k]) for k in ("newton_its", "ksp_its")]
                     + [fmt_mem(r["peak_memory_mb"]),
                        "ok" if r["ok"] else f"**{r['status'].upper()}** (exit {r['exit_code']})"])
            out.append(md_row(cells))
        out.append("")
    out += ["## Pareto fronts", "",
            f"Runs that no other usable run beats in both cost and error (errors within a relative "
            f"{study['error_rtol']:g} counting as equal), by increasing cost.", ""]
    for p in study["problems"]:
        prow = [r for r in rows if r["problem"] == p["name"]]
        for norm in p["norms"]:
            front = pareto_front(prow, norm, study["error_rtol"])
            out += [f"### {p['name']}: {norm}", "",
                    f"| cost [s] | {norm} | level | method | eps rule | solver | memory [MB] |",
                    "|---|---|---|---|---|---|---|"]
            out += [f"| {fmt_time(r['cost'])} | {sci(r[norm], 3)} | {r['level_label']} | {r['method']} "
                    f"| {r['eps_rule']} | {r['solver']} | {fmt_mem(r['peak_memory_mb'])} |"
                    for r in front]
            if not front:
                out.append("| no usable run | | | | | | |")
            out += ["", f"![{p['name']} {norm}]({name}_{p['name']}_{norm}.png)", ""]
    out += ["## Recommendations", "",
            "For each target, the cheapest usable run whose error is at most the target "
            "(generated from the runs above).", ""]
    out += recommendation_table(recs)
    out += [""] + [f"- {sentence(p, n, t, r)}" for p, n, t, r in recs]
    write_lines(path, out)


def write_plot(path, study, problem, norm, rows):
    """Error (log) against cost (log); colour = method + eps rule, marker = solver; the front."""
    combos = [(m["name"], e["name"] if e else NO_EPS) for m in study["methods"]
              for e in (study["eps_rules"] if m["uses_eps"] else [None])]
    if len(combos) <= 9:  # tab10 without its grey, which marks the failed runs
        palette = [plt.get_cmap("tab10")(i) for i in (0, 1, 2, 3, 4, 5, 6, 8, 9)]
    else:
        palette = [plt.get_cmap("tab20")(i) for i in range(20) if i not in (14, 15)]
    colour = {c: palette[i % len(palette)] for i, c in enumerate(combos)}
    shapes = "os^Dv<>pP*h"
    marker = {s["name"]: shapes[i % len(shapes)] for i, s in enumerate(study["solvers"])}
    fig, ax = plt.subplots(figsize=(9.5, 5.5))
    pos = [r for r in rows
           if finite(r["cost"]) and finite(r.get(norm)) and r["cost"] > 0 and r[norm] > 0]
    used_c, used_m, any_failed = set(), set(), False
    for r in pos:
        c = (r["method"], r["eps_rule"])
        if r["ok"]:
            ax.scatter(r["cost"], r[norm], color=colour[c], marker=marker[r["solver"]], s=36,
                       alpha=0.85, edgecolors="none", zorder=3)
            used_c.add(c)
            used_m.add(r["solver"])
        else:
            ax.scatter(r["cost"], r[norm], color="0.5", marker="x", s=40, zorder=2)
            any_failed = True
    front = [r for r in pareto_front(rows, norm, study["error_rtol"])
             if r["cost"] > 0 and r[norm] > 0]
    handles = [Line2D([], [], color=colour[c], marker="o", ls="", label=f"{c[0]}" +
                      ("" if c[1] == NO_EPS else f", eps {c[1]}")) for c in combos if c in used_c]
    handles += [Line2D([], [], color="0.2", marker=marker[s["name"]], ls="", mfc="none",
                       label=s["name"]) for s in study["solvers"] if s["name"] in used_m]
    if any_failed:
        handles.append(Line2D([], [], color="0.5", marker="x", ls="", label="failed (excluded)"))
    if front:
        ax.plot([r["cost"] for r in front], [r[norm] for r in front], "-", color="k", lw=1.2,
                zorder=4)
        ax.scatter([r["cost"] for r in front], [r[norm] for r in front], s=110, facecolors="none",
                   edgecolors="k", linewidths=1.0, zorder=4)
        for k, r in enumerate(front):  # the level, once per run of equal levels along the front
            if k == 0 or front[k - 1]["level_label"] != r["level_label"]:
                ax.annotate(r["level_label"], (r["cost"], r[norm]), textcoords="offset points",
                            xytext=(6, 5), fontsize=7, zorder=5)
        handles.append(Line2D([], [], color="k", marker="o", mfc="none", ms=9,
                              label=f"Pareto front ({len(front)} runs)"))
    if pos:
        ax.set_xscale("log")
        ax.set_yscale("log")
    else:
        no_values_note(ax, norm)
    if pos:  # the targets inside the range of the data (a target far below would squash it)
        lo, hi = min(r[norm] for r in pos), max(r[norm] for r in pos)
        ax.set_ylim(lo / 1.5, hi * 1.5)
        for t in problem["targets"].get(norm, []):
            if lo / 1.5 < t < hi * 1.5:
                ax.axhline(t, color="0.6", lw=0.6, ls=":", zorder=1)
    ax.grid(True, which="both", alpha=0.25)
    ax.set_xlabel(f"cost: {cost_name(problem)} [s]")
    ax.set_ylabel(norm)
    ax.set_title(f"{study['name']}: {problem['name']}, {norm} (dotted: targets)")
    if handles:
        ax.legend(handles=handles, fontsize="small", loc="center left", bbox_to_anchor=(1.01, 0.5))
    save_png(fig, path, 110)


# ------------------------------------------------------------------------------ main

def main(argv=None):
    """Command-line entry point; returns the exit status (0, 1 or 2, see the docstring)."""
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", metavar="STUDY.yaml", help="the trade-off study file")
    ap.add_argument("--outdir", metavar="DIR",
                    help="output directory (default: output/tradeoff/<name>/ in the repository)")
    ap.add_argument("--np", type=int, metavar="N", help="MPI ranks of every run (overrides np:)")
    ap.add_argument("--dry-run", action="store_true", help="print the commands, run nothing")
    ap.add_argument("--quiet", action="store_true",
                    help="do not print the commands as they start (the recommendations are printed)")
    args = ap.parse_args(argv)
    if args.np is not None and args.np < 1:
        ap.error(f"--np must be >= 1, got {args.np}")
    t0 = time.monotonic()
    try:
        study = load_study(args.study)
        outdir = os.path.abspath(args.outdir or os.path.join(ROOT, "output", "tradeoff", study["name"]))
        plan, skipped = plan_runs(study, outdir, args.np)
        for p, m, e, s, why in skipped:
            print(f"skipped: {p['name']} {m['name']}{'' if e is None else ' eps ' + e['name']} "
                  f"{s['name']} (all levels): {why}", file=sys.stderr)
        if args.dry_run:
            print(f"# {len(plan)} runs, in {ROOT}")
            for run in plan:
                print(shlex.join(command(run)))
            return 0
        os.makedirs(outdir, exist_ok=True)
        if not args.quiet:
            print(f"trade-off study {study['name']}: {len(plan)} runs in {ROOT}, output in "
                  f"{display_path(outdir)}", flush=True)
        execute_all(plan, study["timeout"], args.quiet)
    except StudyError as exc:
        print(f"tradeoff.py: error: {exc}", file=sys.stderr)
        return 2
    elapsed = time.monotonic() - t0
    rows = [make_row(r) for r in plan if r.kind == "run"]
    recs = recommendations(study, rows)
    base = os.path.join(outdir, study["name"])
    write_csv(base + ".csv", study, rows)
    write_markdown(base + ".md", study, plan, skipped, rows, recs, elapsed)
    for p in study["problems"]:
        prow = [r for r in rows if r["problem"] == p["name"]]
        for norm in p["norms"]:
            write_plot(f"{base}_{p['name']}_{norm}.png", study, p, norm, prow)
    bad = [r for r in rows if not r["ok"]]
    if bad:
        print(f"WARNING: {len(bad)} of {len(rows)} runs failed (status column; excluded from the "
              f"fronts and recommendations)", file=sys.stderr)
    miss = sorted({k for r in rows for k in r["missing"]})
    if miss:
        print(f"NOTE: attribute(s) missing in some output files, reported as nan: {', '.join(miss)}",
              file=sys.stderr)
    print("\n".join(["## Recommendations", ""] + recommendation_table(recs) + [""]
                    + [sentence(p, n, t, r) for p, n, t, r in recs]))
    print(f"\n{len(rows)} runs + {len(plan) - len(rows)} reference run(s) in {elapsed:.0f} s; wrote "
          f"{display_path(base)}.csv, .md and the plots")
    return 1 if any(r["status"] in ("no output", "timeout") for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
