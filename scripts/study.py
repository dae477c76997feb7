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
import csv
import math
import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from typing import Optional

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

SCRIPTS = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(SCRIPTS)
sys.path.insert(0, SCRIPTS)
import read_runs  # noqa: E402

BIN = "bin/signorini"  # relative to ROOT, the working directory of every run
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1"}
TOP_KEYS = ("name", "description", "np", "options_file", "options", "x", "fit_levels",
            "tolerance", "norms", "series", "levels", "reference", "checks")
REQUIRED_KEYS = ("name", "x", "norms", "series", "levels")
MONOTONE_RTOL = 1e-6     # slack of the monotone-decrease test e_k <= e_{k-1} (1 + MONOTONE_RTOL)
FLOOR_BAND = (0.5, 2.0)  # band around the floor value F that every later e must stay in
LOG_TAIL_LINES = 40      # lines of solver output shown when a run fails without output


class StudyError(Exception):
    """An error in the study file, a run or its output; the message names the culprit."""


# ------------------------------------------------------------------------------ study file

def _check_keys(mapping, allowed, required, where):
    """Raise StudyError if `mapping` is not a dict, lacks a required key or has an unknown one."""
    if not isinstance(mapping, dict):
        raise StudyError(f"{where}: expected a mapping, got {type(mapping).__name__}")
    for key in required:
        if key not in mapping:
            raise StudyError(f"{where}: missing required key '{key}'")
    for key in mapping:
        if key not in allowed:
            raise StudyError(f"{where}: unknown key '{key}' (allowed: {', '.join(allowed)})")


def _number(value, where, integer=False):
    """Return `value` if it is an int (or, unless `integer`, a float); booleans are refused."""
    kinds = (int,) if integer else (int, float)
    if isinstance(value, bool) or not isinstance(value, kinds):
        raise StudyError(f"{where}: expected {'an integer' if integer else 'a number'}, got {value!r}")
    return value


def option_value(value, where):
    """PETSc command-line text of an option value: booleans -> true/false, numbers via repr."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return value
    raise StudyError(f"{where}: option value must be a string, number or boolean, got {value!r}")


def _options(mapping, where):
    """Validate an options mapping; return {key: value text}, keys without the leading dash."""
    if mapping is None:
        return {}
    if not isinstance(mapping, dict):
        raise StudyError(f"{where}: expected a mapping of options, got {type(mapping).__name__}")
    out = {}
    for key, value in mapping.items():
        if not isinstance(key, str):  # YAML 1.1 reads on/off/yes/no as booleans, 1 as a number
            raise StudyError(f"{where}: option key {key!r} was read by YAML as "
                             f"{type(key).__name__}; quote it")
        if not re.fullmatch(r"[A-Za-z0-9_]+", key):
            raise StudyError(f"{where}: invalid option key {key!r} (give it without the dash)")
        if key == "output":
            raise StudyError(f"{where}: option 'output' is set by the driver, remove it")
        out[key] = option_value(value, f"{where}.{key}")
    return out


def safe_label(label):
    """File-name stem of a series label: characters other than [A-Za-z0-9.-] become '_'."""
    return re.sub(r"[^A-Za-z0-9.\-]", "_", label)


def _levels(levels, where):
    """Expand `levels` (a list of option mappings, or {key, values}) to a list of option dicts."""
    if isinstance(levels, dict):
        _check_keys(levels, ("key", "values"), ("key", "values"), where)
        if not isinstance(levels["values"], list):
            raise StudyError(f"{where}.values: expected a list")
        levels = [{levels["key"]: v} for v in levels["values"]]
    if not isinstance(levels, list):
        raise StudyError(f"{where}: expected a list of option mappings or {{key, values}}")
    if len(levels) < 2:
        raise StudyError(f"{where}: a convergence study needs at least 2 levels, got {len(levels)}")
    return [_options(lev, f"{where}[{k}]") for k, lev in enumerate(levels)]


def _series(series, norms, where):
    """Validate the series list; return dicts with label, stem, options and predicted."""
    if not isinstance(series, list) or not series:
        raise StudyError(f"{where}: expected a non-empty list")
    out, stems = [], {}
    for i, s in enumerate(series):
        w = f"{where}[{i}]"
        _check_keys(s, ("label", "options", "predicted"), ("label",), w)
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
            _number(p, f"{w}.predicted.{norm}")
        out.append({"label": label, "stem": stem, "options": _options(s.get("options"), f"{w}.options"),
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
            _check_keys(c, ("type", "norms"), (), w)
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
            _check_keys(c, ("type", "norm", "floor_ratio"), ("norm",), w)
            if c["norm"] not in study["norms"]:
                raise StudyError(f"{w}: '{c['norm']}' is not one of the study's norms")
            ratio = float(_number(c.get("floor_ratio", 0.9), f"{w}.floor_ratio"))
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
    try:
        with open(path) as fh:
            raw = yaml.safe_load(fh)
    except OSError as exc:
        raise StudyError(f"{path}: cannot read the study file ({exc.strerror})") from exc
    except yaml.YAMLError as exc:
        raise StudyError(f"{path}: invalid YAML ({exc})") from exc
    _check_keys(raw, TOP_KEYS, REQUIRED_KEYS, path)

    name = raw["name"]
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9._\-]+", name):
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
        "np": _number(raw.get("np", 1), f"{path}: np", integer=True),
        "options_file": raw.get("options_file"),
        "options": _options(raw.get("options"), f"{path}: options"),
        "x": raw["x"],
        "tolerance": float(_number(raw.get("tolerance", 0.1), f"{path}: tolerance")),
        "norms": norms,
        "levels": _levels(raw["levels"], f"{path}: levels"),
    }
    study["series"] = _series(raw["series"], norms, f"{path}: series")
    if study["np"] < 1:
        raise StudyError(f"{path}: np: must be >= 1, got {study['np']}")
    if study["tolerance"] < 0:
        raise StudyError(f"{path}: tolerance: must be >= 0, got {study['tolerance']}")
    nlev = len(study["levels"])
    study["fit_levels"] = _number(raw.get("fit_levels", nlev), f"{path}: fit_levels", integer=True)
    if not 2 <= study["fit_levels"] <= nlev:
        raise StudyError(f"{path}: fit_levels: must be between 2 and the number of levels "
                         f"({nlev}), got {study['fit_levels']}")

    if study["options_file"] is not None:
        f = study["options_file"]
        if not isinstance(f, str) or not os.path.isfile(os.path.join(ROOT, f)):
            raise StudyError(f"{path}: options_file: no such file {f!r} "
                             f"(relative paths are relative to {ROOT})")

    ref = raw.get("reference")
    if ref is not None:
        _check_keys(ref, ("options", "per"), (), f"{path}: reference")
        per = ref.get("per", "level")
        if per not in ("level", "series"):
            raise StudyError(f"{path}: reference.per: must be 'level' or 'series', got {per!r}")
        ref = {"options": _options(ref.get("options"), f"{path}: reference.options"), "per": per}
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


def display_path(path):
    """`path` relative to ROOT when inside it (as the runs see it), else absolute."""
    path = os.path.abspath(path)
    rel = os.path.relpath(path, ROOT)
    return path if rel.startswith("..") else rel


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
    proc = subprocess.run(cmd, cwd=ROOT, env={**os.environ, **MPI_ENV}, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True)
    log = h5[:-3] + ".log"
    with open(log, "w") as fh:
        fh.write(proc.stdout)
    run.returncode = proc.returncode
    if not os.path.exists(h5):
        tail = "\n".join(proc.stdout.rstrip().splitlines()[-LOG_TAIL_LINES:])
        raise StudyError(f"{run.describe(study)} exited with status {proc.returncode} and wrote no "
                         f"{run.output}; command:\n  {shlex.join(cmd)}\nlast lines of its output "
                         f"(all in {display_path(log)}):\n{tail}")
    try:
        run.attrs = read_runs.read_run(h5)
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

def _invalid(value):
    """Why `value` cannot enter a logarithm ('' when it can: a finite number > 0)."""
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return "not a number"
    if not math.isfinite(value):
        return "not finite"
    if value <= 0:
        return "<= 0"
    return ""


def level_rates(x, e):
    """Level-to-level rates [(rate, note)] for levels 1.., rate = log(e_k/e_{k-1})/log(x_k/x_{k-1}).

    `note` is '' for a valid rate; otherwise rate is nan and note says why.
    """
    out = []
    for k in range(1, len(x)):
        note = _first_invalid(x, e, 0, [k - 1, k])
        if not note and x[k] == x[k - 1]:
            note = f"x_{k} = x_{k - 1}"
        if note:
            out.append((math.nan, note))
        else:
            out.append((math.log(e[k] / e[k - 1]) / math.log(x[k] / x[k - 1]), ""))
    return out


def _first_invalid(x, e, first_level, indices):
    """Note naming the first x or e among `indices` that cannot enter a logarithm ('' if none).

    Levels are numbered from `first_level` (the level of x[0]).
    """
    for name, values in (("x", x), ("e", e)):
        for j in indices:
            why = _invalid(values[j])
            if why:
                return f"{name}_{first_level + j} {why}"
    return ""


def fitted_rate(x, e, first_level=0):
    """Least-squares slope of log e against log x over all given points: (rate, note).

    Every point must be finite and positive, else the rate is nan and the note names the first
    offending level (x[0] being level `first_level`); at least two distinct x are needed.
    """
    note = _first_invalid(x, e, first_level, range(len(x)))
    if note:
        return math.nan, note
    lx, le = np.log(np.asarray(x, float)), np.log(np.asarray(e, float))
    dx = lx - lx.mean()
    sxx = float(dx @ dx)
    if sxx == 0.0:
        return math.nan, "fewer than two distinct x"
    return float(dx @ (le - le.mean())) / sxx, ""


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


def agrees(fitted, predicted, tolerance):
    """Agreement of a fitted rate with a predicted exponent: fitted >= predicted - tolerance."""
    return math.isfinite(fitted) and fitted >= predicted - tolerance


# ------------------------------------------------------------------------------ checks

def monotone_until_floor(x, e, floor_ratio):
    """The monotone check on one series (see the module docstring): (passed, detail)."""
    for k in range(1, len(x)):
        if not x[k] < x[k - 1]:  # also catches nan
            return False, f"x does not decrease along the levels (x_{k - 1} = {x[k - 1]!r}, x_{k} = {x[k]!r})"
    for k, v in enumerate(e):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            return False, f"e_{k} = {v!r} is not a finite number >= 0"
    for k in range(1, len(e)):
        if e[k] > floor_ratio * e[k - 1]:
            floor = e[k - 1]
            lo, hi = FLOOR_BAND[0] * floor, FLOOR_BAND[1] * floor
            for j in range(k, len(e)):
                if not lo <= e[j] <= hi:
                    return False, (f"floor from level {k} at {floor:.4g}, but e_{j} = {e[j]:.4g} "
                                   f"is outside [{lo:.4g}, {hi:.4g}]")
            return True, f"decreases until level {k - 1}, then stays at the floor {floor:.4g}"
        if e[k] > e[k - 1] * (1 + MONOTONE_RTOL):
            return False, f"e increases before the floor: e_{k - 1} = {e[k - 1]:.4g}, e_{k} = {e[k]:.4g}"
    return True, f"decreases over all {len(e)} levels, no floor"


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

def format_rate(rate, note):
    """A rate with 3 decimals, or 'nan (why)'."""
    return f"{rate:.3f}" if not note else f"nan ({note})"


def format_value(v):
    """A norm or abscissa value for the Markdown tables."""
    return f"{v:.4e}" if isinstance(v, float) else str(v)


def _csv_value(v):
    """CSV cell: floats at full precision (repr), None empty, anything else as is."""
    if isinstance(v, float):
        return repr(v)
    return "" if v is None else v


def write_csv(path, study, table, analysis):
    """One row per run; rate_<norm> is empty at level 0 and nan where it cannot be computed."""
    norms = study["norms"]
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["series", "level", study["x"]] + norms
                   + ["newton_its", "ksp_its", "time_solve", "converged", "exit_code"]
                   + [f"rate_{n}" for n in norms] + ["file"])
        for i, row in enumerate(table):
            for k, run in enumerate(row):
                a = run.attrs
                rates = [None if k == 0 else analysis[(i, n)]["rates"][k - 1][0] for n in norms]
                cells = ([study["series"][i]["label"], k, a[study["x"]]] + [a[n] for n in norms]
                         + [a.get("newton_its"), a.get("ksp_its"), a.get("time_solve"),
                            a["converged"], run.returncode] + rates + [os.path.basename(run.output)])
                w.writerow([_csv_value(c) for c in cells])


def _md_options(opts):
    """Options as inline code, '-' if none."""
    return " ".join(f"`-{k} {v}`" for k, v in opts.items()) or "-"


def write_markdown(path, study, plan, table, analysis):
    """The Markdown report: set-up, failed runs, one table per series, the rate summary."""
    x, norms, nfit = study["x"], study["norms"], study["fit_levels"]
    out = [f"# Study {study['name']}", ""]
    if study["description"]:
        out += [study["description"], ""]
    out += [f"- abscissa: `{x}`; fit over the last {nfit} of {len(study['levels'])} levels; "
            f"agreement: fitted >= predicted - {study['tolerance']:g}",
            f"- options file: `{study['options_file']}`" if study["options_file"] else "- options file: -",
            f"- options of every run: {_md_options(study['options'])}"]
    if study["reference"]:
        out.append(f"- reference runs (one per {study['reference']['per']}): "
                   f"{_md_options(study['reference']['options'])}")
    out.append("")
    failed = [r for r in plan if not run_ok(r)]
    if failed:
        out += ["**WARNING: failed runs**", ""]
        out += [f"- {r.describe(study)}: exit status {r.returncode}, converged = "
                f"{r.attrs['converged']} ({r.attrs.get('snes_reason', '?')}), `{r.output}`"
                for r in failed]
        out.append("")
    for i, s in enumerate(study["series"]):
        out += [f"## Series {s['label']}", "", f"Options: {_md_options(s['options'])}", ""]
        head = ["level", "level options", x]
        for n in norms:
            head += [n, f"rate {n}"]
        head += ["newton_its", "ksp_its", "converged"]
        out += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for k, run in enumerate(table[i]):
            cells = [str(k), _md_options(study["levels"][k]), format_value(run.attrs[x])]
            for n in norms:
                a = analysis[(i, n)]
                cells += [format_value(a["e"][k]), "" if k == 0 else format_rate(*a["rates"][k - 1])]
            cells += [str(run.attrs.get("newton_its", "")), str(run.attrs.get("ksp_its", "")),
                      "yes" if run_ok(run) else f"**NO** (exit {run.returncode})"]
            out.append("| " + " | ".join(cells) + " |")
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
    with open(path, "w") as fh:
        fh.write("\n".join(out) + "\n")


def write_plot(path, study, norm, analysis):
    """Log-log plot of `norm` against the abscissa for all series, with predicted slopes."""
    markers = "os^vDPX*<>"
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    plotted = False
    for i, s in enumerate(study["series"]):
        x, e = analysis["x"][i], analysis[(i, norm)]["e"]
        pts = [(a, b) for a, b in zip(x, e) if not _invalid(a) and not _invalid(b)]
        if not pts:
            continue
        plotted = True
        rate, note = analysis[(i, norm)]["fit"]
        px, pe = zip(*pts)
        line, = ax.plot(px, pe, marker=markers[i % len(markers)], label=
                        f"{s['label']} (fitted {'nan' if note else f'{rate:.2f}'})")
        p = s["predicted"].get(norm)
        if p is not None and not _invalid(x[-1]) and not _invalid(e[-1]):
            xs = np.array([min(px), max(px)])
            ax.plot(xs, e[-1] * (xs / x[-1]) ** p, "--", color=line.get_color(),
                    label=f"slope {p:g} ({s['label']})")
    ax.set_xscale("log")
    ax.set_yscale("log")
    if plotted:
        ax.legend(fontsize="small")
    else:
        ax.text(0.5, 0.5, f"no finite positive values of {norm}", ha="center", va="center",
                transform=ax.transAxes)
    ax.grid(True, which="both", alpha=0.3)
    ax.set_xlabel(study["x"])
    ax.set_ylabel(norm)
    ax.set_title(f"{study['name']}: {norm}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


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
