"""Tests of scripts/tradeoff.py (make test): the Pareto front and the recommendations on synthetic rows, the
validation of the study file, and a tiny real grid run end to end. Each test writes its files in a temporary
directory of its own (TMP)."""
import csv
import math
import os
import random
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import tradeoff  # noqa: E402
from study import StudyError  # noqa: E402

SCRIPT = os.path.join(ROOT, "scripts", "tradeoff.py")
TMP = None  # the test's own temporary directory, set by the fixture tmp
NAN = float("nan")


@pytest.fixture(autouse=True)
def tmp(tmp_path):
    """Every test writes its study files and outputs in a temporary directory of its own (pytest's tmp_path)."""
    global TMP
    TMP = str(tmp_path)
    return TMP


def write(name, text):
    """Write `text` to TMP/name; return the path."""
    path = os.path.join(TMP, name)
    with open(path, "w") as fh:
        fh.write(text)
    return path


def cli(*args):
    """Run tradeoff.py with `args`; return the CompletedProcess (text stdout, stderr)."""
    return subprocess.run([sys.executable, SCRIPT] + list(args), cwd=ROOT, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, timeout=120)


_INDEX = [0]


def row(cost, err, ok=True, **kw):
    """A synthetic analysed row with norm 'e'; index increases in creation order (plan order)."""
    _INDEX[0] += 1
    r = {"problem": "p", "level": 0, "level_label": "64x64", "method": "penalty_gauss",
         "method_text": "penalty gauss", "eps_rule": "h", "eps_text": "eps = h", "solver": "mumps",
         "solver_text": "mumps", "cost": cost, "e": err, "ok": ok, "status": "ok" if ok else "failed",
         "peak_memory_mb": 45.0, "index": _INDEX[0]}
    r.update(kw)
    return r


def points(rows):
    return [(r["cost"], r["e"]) for r in rows]


# ------------------------------------------------------------------------------ Pareto front

def test_pareto_front_basic():
    rows = [row(1, 1.0), row(2, 0.5), row(3, 0.6), row(4, 0.1), row(0.5, 2.0), row(5, 0.2)]
    assert points(tradeoff.pareto_front(rows, "e")) == [(0.5, 2.0), (1, 1.0), (2, 0.5), (4, 0.1)]


def test_pareto_front_excludes_failed_runs():
    bad = row(0.1, 1e-6, ok=False)  # would dominate every other run
    rows = [row(1, 1.0), bad, row(2, 0.5)]
    front = tradeoff.pareto_front(rows, "e")
    assert bad not in front
    assert points(front) == [(1, 1.0), (2, 0.5)]
    assert tradeoff.pareto_front([bad], "e") == []


def test_pareto_front_ties():
    a, b = row(1, 0.5), row(1, 0.5)          # identical: both kept, in plan order
    same_cost_worse = row(1, 0.6)             # dominated by a (same cost, larger error)
    same_err_slower = row(2, 0.5)             # dominated by a (same error, larger cost)
    c = row(3, 0.1)
    front = tradeoff.pareto_front([same_err_slower, c, same_cost_worse, b, a], "e")
    assert front == [b, a, c] or front == [a, b, c], points(front)
    assert [r["index"] for r in front[:2]] == sorted([a["index"], b["index"]])
    assert same_cost_worse not in front and same_err_slower not in front


def test_pareto_front_skips_nan():
    rows = [row(NAN, 0.01), row(1, NAN), row(2, 0.5), row(3, math.inf)]
    assert points(tradeoff.pareto_front(rows, "e")) == [(2, 0.5)]


def test_pareto_front_matches_brute_force():
    rng = random.Random(7)
    rows = [row(rng.choice([1, 2, 3, 4, 5]) * rng.random(), rng.choice([0.1, 0.2, rng.random()]),
                ok=rng.random() > 0.2) for _ in range(200)]
    front = tradeoff.pareto_front(rows, "e", rtol=0.0)
    # independent sweep: by increasing (cost, error), a run is on the front iff its error is below
    # that of every cheaper run, or it equals the previous front point in cost and error
    sweep, best = [], math.inf
    for r in sorted((r for r in rows if r["ok"]), key=lambda r: (r["cost"], r["e"])):
        if r["e"] < best or (sweep and (r["cost"], r["e"]) == (sweep[-1]["cost"], sweep[-1]["e"])):
            sweep.append(r)
            best = min(best, r["e"])
    assert sorted(r["index"] for r in front) == sorted(r["index"] for r in sweep)
    costs = [r["cost"] for r in front]
    assert costs == sorted(costs)


def test_pareto_front_round_off_tolerance():
    fast, slow = row(1.0, 1.0e-2), row(100.0, 1.0e-2 * (1 - 1e-12))  # same solution, slower solver
    better = row(5.0, 0.9e-2)
    assert tradeoff.pareto_front([slow, fast, better], "e") == [fast, better]
    assert tradeoff.pareto_front([slow, fast], "e") == [fast]
    assert tradeoff.pareto_front([slow, fast], "e", rtol=0.0) == [fast, slow]
    a, b = row(1.0, 1e-2), row(1.0, 1e-2 * (1 + 1e-9))  # equal cost and error: both kept
    assert tradeoff.pareto_front([a, b], "e") == [a, b]


# ------------------------------------------------------------------------------ recommendations

def test_recommend_cheapest_reaching_the_target():
    rows = [row(1, 0.3), row(2, 0.05), row(3, 0.01), row(10, 0.001)]
    assert tradeoff.recommend(rows, "e", 0.1) is rows[1]
    assert tradeoff.recommend(rows, "e", 0.01) is rows[2]  # error == target reaches it
    assert tradeoff.recommend(rows, "e", 1.0) is rows[0]


def test_recommend_excludes_failed_runs():
    bad = row(0.5, 0.001, ok=False)
    rows = [row(1, 0.3), bad, row(4, 0.02)]
    assert tradeoff.recommend(rows, "e", 0.05) is rows[2]
    assert tradeoff.recommend([bad], "e", 1.0) is None


def test_recommend_target_nobody_reaches():
    rows = [row(1, 0.3), row(2, 0.05)]
    assert tradeoff.recommend(rows, "e", 0.01) is None
    p = {"name": "mms2d"}
    assert tradeoff.sentence(p, "error_h1", 0.01, None) == \
        "For error_h1 <= 1e-2 on mms2d: none reaches it."
    table = tradeoff.recommendation_table([(p, "error_h1", 0.01, None)])
    assert "| mms2d | error_h1 | 1e-2 | none reaches it |" in table[-1], table


def test_recommend_ties():
    a, b, c = row(1, 0.05), row(1, 0.02), row(1, 0.02)
    assert tradeoff.recommend([a, c, b], "e", 0.1) is b  # equal cost: smaller error, then plan order
    assert tradeoff.recommend([a, b, c], "e", 0.1) is b


def test_recommendation_lies_on_the_front():
    rng = random.Random(3)
    rows = [row(rng.random() * 10, rng.random(), ok=rng.random() > 0.3) for _ in range(100)]
    front = tradeoff.pareto_front(rows, "e")
    for t in (0.9, 0.5, 0.1, 0.03, 0.01, 1e-4):
        r = tradeoff.recommend(rows, "e", t)
        if r is None:
            assert all(x["e"] > t for x in rows if x["ok"])
        else:
            assert r in front and r["ok"] and r["e"] <= t


def test_sentence_format():
    p = {"name": "mms2d"}
    r = row(0.2134, NAN, peak_memory_mb=45.2, error_h1=8.1e-3)
    assert tradeoff.sentence(p, "error_h1", 1e-2, r) == ("For error_h1 <= 1e-2 on mms2d use penalty "
                                                         "gauss, eps = h, mumps on 64x64: 0.213 s, "
                                                         "45 MB (error 8.1e-3)")
    vi = row(1.5, NAN, method="vi", method_text="SNESVI", eps_rule="-", eps_text="",
             peak_memory_mb=NAN, error_h1=3e-3)
    assert tradeoff.sentence(p, "error_h1", 3e-3, vi) == ("For error_h1 <= 3e-3 on mms2d use SNESVI, "
                                                          "mumps on 64x64: 1.5 s, memory n/a "
                                                          "(error 3.0e-3)")


def test_recommendations_over_problems_norms_targets():
    s = tradeoff.load_study(write("rec.yaml", SYNTH))
    rows = [row(1, NAN, problem="a", error_h1=0.2, error_l2=0.02),
            row(2, NAN, problem="a", error_h1=0.05, error_l2=0.01),
            row(1, NAN, problem="b", error_h1=0.01, error_l2=0.001)]
    recs = tradeoff.recommendations(s, rows)
    got = [(p["name"], n, t, None if r is None else r["index"]) for p, n, t, r in recs]
    assert got == [("a", "error_h1", 0.1, rows[1]["index"]), ("a", "error_h1", 0.01, None),
                   ("b", "error_h1", 0.1, rows[2]["index"]), ("b", "error_h1", 0.01, rows[2]["index"]),
                   ("b", "error_l2", 0.05, rows[2]["index"])], got


def test_missing_attribute_is_nan_with_a_note():
    s = tradeoff.load_study(write("miss.yaml", SYNTH))
    plan, _ = tradeoff.plan_runs(s, TMP)
    run = plan[0]
    run.attrs = {"converged": 1, "h": 0.1, "eps": 0.1, "n_dofs": 10, "time_setup": 0.1,
                 "time_solve": 0.2, "time_total": 0.4, "newton_its": 3, "ksp_its": 3,
                 "error_h1": 0.05}
    run.returncode, run.status = 0, "ok"
    r = tradeoff.make_row(run)
    assert math.isnan(r["peak_memory_mb"]) and "peak_memory_mb" in r["missing"]
    assert any("missing: peak_memory_mb" in n for n in r["notes"])
    assert r["cost"] == 0.4 and tradeoff.usable(r, "error_h1")


# ------------------------------------------------------------------------------ study file

SYNTH = """\
name: syn
norms: [error_h1]
targets: {error_h1: [1e-1, 1e-2], error_l2: ["5e-2"]}
problems:
  - name: a
    options_file: options/mms.yaml
    levels: {key: dm_plex_box_faces, values: ["8,8", "16,16"]}
  - name: b
    norms: [error_h1, error_l2]
    levels: [{dm_refine: 0}]
methods:
  - {name: pg, options: {contact_method: penalty}}
  - {name: vi, options: {contact_method: vi}, uses_eps: false}
eps_rules:
  - {name: h, options: {penalty_eps_power: 1}}
  - {name: h2, options: {penalty_eps_power: 2}}
solvers:
  - {name: mumps, options_file: options/solvers/mumps.yaml}
  - {name: gamg, options_file: options/solvers/gamg.yaml}
skip:
  - {method: vi, solver: gamg, reason: refused}
"""


def expect_error(text, *fragments):
    """load_study on `text` must raise StudyError whose message contains every fragment."""
    path = write("err.yaml", text)
    try:
        tradeoff.load_study(path)
    except StudyError as exc:
        for f in fragments:
            assert f in str(exc), f"message {str(exc)!r} lacks {f!r}"
        return
    raise AssertionError(f"no StudyError for:\n{text}")


def test_study_file_valid():
    s = tradeoff.load_study(write("ok.yaml", SYNTH))
    assert s["problems"][0]["targets"] == {"error_h1": [0.1, 0.01]}
    assert s["problems"][1]["targets"]["error_l2"] == [0.05]  # '5e-2' read as text is accepted
    assert [lev["label"] for lev in s["problems"][0]["levels"]] == ["8x8", "16x16"]
    assert s["problems"][0]["cost"] == ["time_total"]


def test_study_file_errors_name_the_key():
    cases = [
        (SYNTH.replace("targets: {error_h1: [1e-1, 1e-2], error_l2: [\"5e-2\"]}\n", ""),
         ["missing required key 'targets'"]),
        (SYNTH + "colour: red\n", ["unknown key 'colour'"]),
        (SYNTH.replace("error_h1: [1e-1, 1e-2]", "error_h1: [1e-1, -3]"),
         ["targets.error_h1[1]"]),
        (SYNTH.replace("error_h1: [1e-1, 1e-2]", "error_h1: [1e-1, lots]"),
         ["targets.error_h1[1]", "'lots'"]),
        (SYNTH.replace("norms: [error_h1, error_l2]", "norms: [error_h1, error_energy]"),
         ["problems[1].norms", "error_energy"]),
        (SYNTH.replace("    levels: [{dm_refine: 0}]\n", ""),
         ["problems[1]", "missing required key 'levels'"]),
        (SYNTH.replace("levels: [{dm_refine: 0}]", "levels: []"), ["problems[1].levels"]),
        (SYNTH.replace("values: [\"8,8\", \"16,16\"]}", "values: [\"8,8\"], labels: [a, b]}"),
         ["problems[0].levels.labels"]),
        (SYNTH.replace("uses_eps: false", "uses_eps: maybe"), ["methods[1].uses_eps"]),
        (SYNTH.replace("{name: vi,", "{name: pg,"), ["methods[1].name", "'pg'"]),
        (SYNTH.replace("{method: vi, solver: gamg,", "{method: vi, solver: amg,"),
         ["skip[0].solver", "'amg'"]),
        (SYNTH.replace("{method: vi, solver: gamg, reason: refused}", "{method: vi}"),
         ["skip[0]", "missing required key 'reason'"]),
        (SYNTH.replace("options: {contact_method: vi}", "options: {output: x.h5}"),
         ["methods[1].options.output"]),
        (SYNTH.replace("options_file: options/mms.yaml", "options_file: options/nope.yaml"),
         ["problems[0].options_file", "nope.yaml"]),
        (SYNTH.replace("eps_rules:\n  - {name: h, options: {penalty_eps_power: 1}}\n"
                       "  - {name: h2, options: {penalty_eps_power: 2}}\n", ""),
         ["eps_rules", "pg"]),
        (SYNTH.replace("    levels: [{dm_refine: 0}]\n",
                       "    levels: [{dm_refine: 0}]\n    reference: {options: {dm_refine: 2}, "
                       "solver: superlu}\n"), ["problems[1].reference.solver", "superlu"]),
        (SYNTH.replace("  - name: b\n", "  - name: a\n"), ["problems[1].name", "twice"]),
        (SYNTH.replace("name: syn", "name: my study"), ["name"]),
        (SYNTH.replace("norms: [error_h1]\n", ""), ["problems[0]", "'norms'"]),
        (SYNTH + "np: 0\n", ["np"]),
        (SYNTH + "cost: []\n", ["cost"]),
    ]
    for text, fragments in cases:
        expect_error(text, *fragments)


def test_plan_skips_and_runs_vi_once_per_solver():
    s = tradeoff.load_study(write("plan.yaml", SYNTH.replace(
        "    levels: [{dm_refine: 0}]\n",
        "    levels: [{dm_refine: 0}]\n    reference: {options: {dm_refine: 2, contact_method: vi}, "
        "solver: mumps}\n")))
    plan, skipped = tradeoff.plan_runs(s, TMP)
    assert plan[0].kind == "reference" and plan[0].problem["name"] == "b"
    runs = [r for r in plan if r.kind == "run"]
    # per level: pg x {h, h2} x {mumps, gamg} = 4, vi x {mumps} = 1 (vi + gamg skipped)
    assert len(runs) == 5 * (2 + 1), len(runs)
    assert [(p["name"], m["name"], s_["name"]) for p, m, e, s_, _ in skipped] == \
        [("a", "vi", "gamg"), ("b", "vi", "gamg")]
    vi = [r for r in runs if r.method["name"] == "vi"]
    assert all(r.eps_rule is None and r.solver["name"] == "mumps" for r in vi)
    assert all("penalty_eps_power" not in " ".join(r.args) for r in vi)
    ref = plan[0].output
    assert all(r.args[-2:] == ["-reference", ref] for r in runs if r.problem["name"] == "b")
    assert all("-reference" not in r.args for r in runs if r.problem["name"] == "a")
    assert len({r.output for r in plan}) == len(plan)


def test_dry_run_prints_every_command():
    p = cli(write("dry.yaml", SYNTH), "--dry-run", "--outdir", os.path.join(TMP, "dry"))
    assert p.returncode == 0, p.stderr
    cmds = [ln for ln in p.stdout.splitlines() if ln.startswith("mpiexec")]
    assert len(cmds) == 15, p.stdout
    assert "vi gamg" in p.stderr and "refused" in p.stderr
    assert not os.path.exists(os.path.join(TMP, "dry"))
    p = cli(write("bad.yaml", SYNTH + "colour: red\n"), "--dry-run")
    assert p.returncode == 2 and "unknown key 'colour'" in p.stderr, p.stderr


# ------------------------------------------------------------------------------ end to end

TINY = """\
name: tiny
norms: [error_h1, error_pressure_l2]
targets:
  error_h1: [3e-1, 1.5e-1, 1e-3]
  error_pressure_l2: [5e-2, 1e-2]
problems:
  - name: mms2d
    options_file: options/mms.yaml
    options: {dm_plex_dim: 2}
    levels: {key: dm_plex_box_faces, values: ["8,8", "16,16"]}
methods:
  - name: penalty_gauss
    text: penalty gauss
    options: {contact_method: penalty, penalty_quadrature: gauss}
  - {name: vi, text: SNESVI, options: {contact_method: vi}, uses_eps: false}
eps_rules:
  - {name: h, text: eps = h, options: {penalty_eps_power: 1}}
solvers:
  - {name: mumps, options_file: options/solvers/mumps.yaml}
  - {name: gamg, options_file: options/solvers/gamg.yaml}
skip:
  - {method: vi, solver: gamg, reason: refused by the solver}
"""


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_end_to_end_tiny_grid():
    out = os.path.join(TMP, "tiny")
    p = cli(write("tiny.yaml", TINY), "--outdir", out, "--quiet")
    assert p.returncode == 0, p.stdout + p.stderr
    rows = read_csv(os.path.join(out, "tiny.csv"))
    got = sorted((r["level_label"], r["method"], r["eps_rule"], r["solver"]) for r in rows)
    levels = ("8x8", "16x16")
    want = sorted([(lev, "penalty_gauss", "h", s) for lev in levels for s in ("mumps", "gamg")]
                  + [(lev, "vi", "-", "mumps") for lev in levels])
    assert got == want, got
    for r in rows:
        assert r["status"] == "ok" and r["converged"] == "1", r
        assert float(r["error_h1"]) > 0 and float(r["time_total"]) > 0 and float(r["cost"]) > 0
        assert os.path.exists(os.path.join(out, r["file"]))
        for col in ("h", "eps", "n_dofs", "error_pressure_l2", "time_setup", "time_solve",
                    "newton_its", "ksp_its", "peak_memory_mb", "file"):
            assert col in r, col
        if math.isnan(float(r["peak_memory_mb"])):
            assert "missing: peak_memory_mb" in r["notes"], r["notes"]
    md = open(os.path.join(out, "tiny.md")).read()
    assert "## Recommendations" in md and "## Pareto fronts" in md and "## Problem mms2d" in md
    assert "| problem | norm | target | method | eps rule | solver | level | cost [s] |" in md
    assert "| mms2d | vi | - | gamg | refused by the solver |" in md  # the skipped combination
    rec = md.split("## Recommendations", 1)[1]
    for norm, t in (("error_h1", "3e-1"), ("error_h1", "1.5e-1"), ("error_h1", "1e-3"),
                    ("error_pressure_l2", "5e-2"), ("error_pressure_l2", "1e-2")):
        assert f"| mms2d | {norm} | {t} |" in rec, (norm, t)
    assert "| mms2d | error_h1 | 1e-3 | none reaches it |" in rec
    # the recommendation of 3e-1 is the fastest run of all with error_h1 <= 0.3
    ok = [r for r in rows if float(r["error_h1"]) <= 0.3]
    best = min(ok, key=lambda r: float(r["cost"]))
    line = [ln for ln in rec.splitlines() if ln.startswith("| mms2d | error_h1 | 3e-1 |")][0]
    assert (f"| {best['method']} | {best['eps_rule']} | {best['solver']} | "
            f"{best['level_label']} |") in line, (line, best)
    assert "For error_h1 <= 1e-3 on mms2d: none reaches it." in p.stdout
    assert "For error_h1 <= 3e-1 on mms2d use " in p.stdout
    assert "| problem | norm | target |" in p.stdout
    for norm in ("error_h1", "error_pressure_l2"):
        assert os.path.getsize(os.path.join(out, f"tiny_mms2d_{norm}.png")) > 1000


def test_end_to_end_failed_run_is_shown_not_recommended():
    text = TINY.replace('values: ["8,8", "16,16"]', 'values: ["8,8"]').replace(
        "options: {dm_plex_dim: 2}", "options: {dm_plex_dim: 2, snes_max_it: 1}").replace(
        "  - {name: vi, text: SNESVI, options: {contact_method: vi}, uses_eps: false}\n", "").replace(
        "  - {name: gamg, options_file: options/solvers/gamg.yaml}\n", "").replace(
        "skip:\n  - {method: vi, solver: gamg, reason: refused by the solver}\n", "").replace(
        "name: tiny", "name: fail")
    out = os.path.join(TMP, "fail")
    p = cli(write("fail.yaml", text), "--outdir", out, "--quiet")
    assert p.returncode == 0, p.stdout + p.stderr  # a Newton failure is a result, not an error
    rows = read_csv(os.path.join(out, "fail.csv"))
    assert len(rows) == 1 and rows[0]["status"] == "failed" and rows[0]["converged"] == "0"
    assert rows[0]["exit_code"] == "3"
    md = open(os.path.join(out, "fail.md")).read()
    assert "## Failed runs" in md and "**FAILED** (exit 3)" in md
    assert "| mms2d | error_h1 | 3e-1 | none reaches it |" in md
    assert "FAILED" in p.stderr

