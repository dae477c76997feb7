"""Tests of scripts/study.py (make test): rates and checks on synthetic data, the study file, and small real
studies of the square scene run end to end. Each test writes its files in a temporary directory of its own (TMP)."""
import csv
import math
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import study  # noqa: E402

STUDY = os.path.join(ROOT, "scripts", "study.py")
TMP = None  # the test's own temporary directory, set by the fixture tmp


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
    """Run study.py with `args`; return the CompletedProcess (text stdout, stderr)."""
    return subprocess.run([sys.executable, STUDY] + list(args), cwd=ROOT, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, timeout=300)


def expect_study_error(text, *fragments):
    """load_study on `text` must raise StudyError whose message contains every fragment."""
    path = write("err.yaml", text)
    try:
        study.load_study(path)
    except study.StudyError as exc:
        for f in fragments:
            assert f in str(exc), f"message {str(exc)!r} lacks {f!r}"
        return
    raise AssertionError(f"no StudyError for:\n{text}")


MINIMAL = """\
name: syn
x: h
norms: [e1, e2]
series:
  - {label: a, predicted: {e1: 2.0}}
  - {label: b, predicted: {e1: 2.0, e2: 1.0}}
levels: {key: dm_plex_box_faces, values: ["4,4", "8,8", "16,16", "32,32"]}
"""


def synthetic(study_text, values, converged=None):
    """A loaded study and a fake executed plan: values[i][k] is the /run dict of series i level k."""
    s = study.load_study(write("syn.yaml", study_text))
    plan = study.plan_runs(s, TMP)
    for run in plan:
        run.attrs = dict(values[run.series][run.level], converged=1)
        run.returncode = 0
        if converged and (run.series, run.level) in converged:
            run.attrs["converged"], run.returncode = 0, 3
    return s, plan, study.analyse(s, study.run_table(plan, s))


# ---------------------------------------------------------------- rates

def test_rates_of_an_exact_power_law():
    for r in (0.5, 0.6875, 1.0, 2.0, 3.7):
        for x in ([0.5, 0.25, 0.125, 0.0625], [0.3, 0.17, 0.05, 0.011]):  # uniform and irregular
            e = [3.7 * h ** r for h in x]
            rate, note = study.fitted_rate(x, e)
            assert note == "" and abs(rate - r) < 1e-12, f"fitted {rate!r} for r = {r}"
            for rk, nk in study.level_rates(x, e):
                assert nk == "" and abs(rk - r) < 1e-12, f"level rate {rk!r} for r = {r}"


def test_fit_uses_only_the_last_fit_levels():
    h = [0.5, 0.25, 0.125, 0.0625]
    vals = [[{"h": x, "e1": (1.0 if k == 0 else x ** 2), "e2": x} for k, x in enumerate(h)]] * 2
    s, _, a = synthetic(MINIMAL + "fit_levels: 3\n", vals)
    rate, note = a[(0, "e1")]["fit"]
    assert note == "" and abs(rate - 2.0) < 1e-12, f"fit over the last 3 levels gave {rate!r}"
    s, _, a = synthetic(MINIMAL, vals)  # default: all levels, the polluted first one included
    assert abs(a[(0, "e1")]["fit"][0] - 2.0) > 0.1


def test_zero_negative_and_missing_values_give_nan_with_a_reason():
    x = [0.5, 0.25, 0.125, 0.0625]
    for bad, why in ((0.0, "<= 0"), (-1e-3, "<= 0"), (math.nan, "not finite"), (None, "not a number")):
        e = [1.0, 0.5, bad, 0.1]
        rate, note = study.fitted_rate(x, e)
        assert math.isnan(rate) and note == f"e_2 {why}", (rate, note)
        rates = study.level_rates(x, e)
        assert rates[0][1] == "" and abs(rates[0][0] - 1.0) < 1e-12
        assert all(math.isnan(r) and n == f"e_2 {why}" for r, n in rates[1:]), rates
    rate, note = study.fitted_rate([0.1, 0.1], [1.0, 0.5])
    assert math.isnan(rate) and "distinct" in note
    # level numbering of the note in the whole series when only the last levels are fitted
    vals = [[{"h": x, "e1": (0.0 if k == 3 else x), "e2": x} for k, x in enumerate(x)]] * 2
    _, _, a = synthetic(MINIMAL + "fit_levels: 2\n", vals)
    assert math.isnan(a[(0, "e1")]["fit"][0]) and a[(0, "e1")]["fit"][1] == "e_3 <= 0"


# ---------------------------------------------------------------- checks

def test_monotone_check_on_synthetic_series():
    x = [1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125]
    cases = [  # (e, floor_ratio, expected to pass)
        ([1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125], 0.9, True),   # clean decrease, no floor
        ([1.0, 0.5, 0.25, 0.24, 0.245, 0.25], 0.9, True),        # stagnates at a floor
        ([1.0, 0.5, 0.25, 0.26, 0.14, 0.2], 0.9, True),          # noisy floor within [F/2, 2F]
        ([1.0, 0.5, 0.0, 0.0, 0.0, 0.0], 0.9, True),             # exact from level 2 on
        ([1.0, 0.5, 0.6, 0.3, 0.15, 0.07], 0.9, False),          # increases, then keeps falling
        ([1.0, 0.5, 0.55, 0.2, 0.1, 0.05], 1.5, False),          # increases before the floor
        ([1.0, 0.5, 0.25, 0.6, 0.6, 0.6], 0.9, False),           # jumps above 2 F at the floor
        ([1.0, 0.5, 0.25, 0.24, 0.1, 0.05], 0.9, False),         # leaves the floor band downward
        ([1.0, 0.5, math.nan, 0.1, 0.05, 0.02], 0.9, False),     # missing value
    ]
    for e, ratio, expected in cases:
        ok, detail = study.monotone_until_floor(x, e, ratio)
        assert ok == expected, f"{e} floor_ratio {ratio}: {ok} ({detail}), expected {expected}"
    ok, detail = study.monotone_until_floor([0.1, 0.2, 0.05], [1.0, 0.5, 0.25], 0.9)
    assert not ok and "x does not decrease" in detail


def test_rate_and_converged_checks_on_synthetic_data():
    h = [0.5, 0.25, 0.125, 0.0625]
    text = MINIMAL + "fit_levels: 3\ntolerance: 0.1\nchecks:\n  - {type: rate}\n" \
                     "  - {type: monotone, norm: e2}\n"
    # series a: e1 ~ h^1.95 (agrees with 2 - 0.1); series b: e1 ~ h^2, e2 ~ h^1 (agree)
    good = [[{"h": x, "e1": x ** 1.95, "e2": x} for x in h], [{"h": x, "e1": x ** 2, "e2": x} for x in h]]
    s, plan, a = synthetic(text, good)
    results = study.evaluate_checks(s, plan, a)
    assert len(results) == 3 and all(ok for ok, _ in results), results
    # series a too slow (1.85 < 1.9), series b's e2 increasing: both checks fail
    bad = [[{"h": x, "e1": x ** 1.85, "e2": x} for x in h], [{"h": x, "e1": x ** 2, "e2": 1 / x} for x in h]]
    s, plan, a = synthetic(text, bad)
    results = study.evaluate_checks(s, plan, a)
    assert [ok for ok, _ in results] == [True, False, False], results
    assert "a e1: fitted 1.850 NOT >= 2 - 0.1" in results[1][1], results[1][1]
    # a non-converged run fails the implicit check only
    s, plan, a = synthetic(text, good, converged={(1, 2)})
    results = study.evaluate_checks(s, plan, a)
    assert [ok for ok, _ in results] == [False, True, True], results
    assert "series 'b' level 2" in results[0][1]


def test_agreement_is_one_sided():
    assert study.agrees(2.5, 2.0, 0.1) and study.agrees(1.9, 2.0, 0.1)
    assert not study.agrees(1.89, 2.0, 0.1) and not study.agrees(math.nan, 2.0, 0.1)


# ---------------------------------------------------------------- study file

def test_study_file_errors_name_the_key():
    expect_study_error(MINIMAL.replace("x: h\n", ""), "missing required key 'x'")
    expect_study_error(MINIMAL.replace("norms: [e1, e2]\n", ""), "missing required key 'norms'")
    expect_study_error(MINIMAL + "colour: red\n", "unknown key 'colour'")
    expect_study_error(MINIMAL.replace("{label: a, ", "{label: a, optons: {}, "), "unknown key 'optons'")
    expect_study_error(MINIMAL.replace("e2: 1.0", "e3: 1.0"), "'e3' is not one of the study's norms")
    expect_study_error(MINIMAL + "fit_levels: 5\n", "fit_levels")
    expect_study_error(MINIMAL + "options: {output: x.h5}\n", "'output'")
    expect_study_error(MINIMAL + "options: {-dm_refine: 1}\n", "without the dash")
    expect_study_error(MINIMAL + "options: {off: 1}\n", "option key False was read by YAML as bool")
    expect_study_error(MINIMAL + "checks: [{type: rate, norms: [e2]}, {type: monotone}]\n",
                       "missing required key 'norm'")
    expect_study_error(MINIMAL.replace("e2: 1.0", "e1: 1.0") + "checks: [{type: rate, norms: [e2]}]\n",
                       "no series predicts a rate for 'e2'")
    expect_study_error(MINIMAL + "reference: {per: cell}\n", "'level' or 'series'")
    expect_study_error(MINIMAL.replace("label: b", "label: a"), "same file name")


def test_options_precedence_levels_form_and_reference_order():
    text = """\
name: prec
np: 2
options: {a: 1, b: 1, c: 1, d: 1, flag: true, eps: 0.001}
x: eps
norms: [e]
series:
  - {label: "s=1", options: {b: 2, c: 2, d: 2, quiet: false}}
levels:
  - {c: 3, d: 3}
  - {c: 4, d: 4}
reference: {options: {d: ref}, per: level}
"""
    s = study.load_study(write("prec.yaml", text))
    plan = study.plan_runs(s, os.path.join(ROOT, "output", "x"))
    assert [(r.kind, r.level) for r in plan] == [("reference", 0), ("run", 0), ("reference", 1), ("run", 1)]
    ref0, run0 = plan[0], plan[1]
    assert run0.options == {"a": "1", "b": "2", "c": "3", "d": "3", "flag": "true", "eps": "0.001",
                            "quiet": "false"}, run0.options
    assert ref0.options["d"] == "ref" and ref0.options["c"] == "3" and ref0.reference is None
    assert run0.reference == ref0.output == os.path.join("output", "x", "s_1_0_ref.h5")
    cmd = study.command(run0, s, s["np"])
    assert cmd[:4] == ["mpiexec", "-n", "2", "bin/signorini"] and cmd[-2:] == ["-output", "output/x/s_1_0.h5"]
    assert cmd[cmd.index("-reference") + 1] == ref0.output and cmd[cmd.index("-flag") + 1] == "true"
    # per: series -> one reference, before the levels, with the options of the last level
    s = study.load_study(write("prec2.yaml", text.replace("per: level", "per: series")))
    plan = study.plan_runs(s, TMP)
    assert [(r.kind, r.level) for r in plan] == [("reference", None), ("run", 0), ("run", 1)]
    assert plan[0].options["c"] == "4" and plan[1].reference == plan[2].reference == plan[0].output
    # the {key, values} form of the levels expands to the list form
    a = study.load_study(write("l1.yaml", MINIMAL))
    b = study.load_study(write("l2.yaml", MINIMAL.replace(
        'levels: {key: dm_plex_box_faces, values: ["4,4", "8,8", "16,16", "32,32"]}',
        'levels: [{dm_plex_box_faces: "4,4"}, {dm_plex_box_faces: "8,8"}, '
        '{dm_plex_box_faces: "16,16"}, {dm_plex_box_faces: "32,32"}]')))
    assert a["levels"] == b["levels"]


def test_cli_missing_file_and_dry_run():
    p = cli(os.path.join(TMP, "no_such_study.yaml"))
    assert p.returncode == 2 and "no_such_study.yaml" in p.stderr, p.stderr
    out = os.path.join(TMP, "dry")
    p = cli(write("dry.yaml", MINIMAL), "--dry-run", "--outdir", out, "--np", "3")
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("mpiexec")]
    assert p.returncode == 0 and len(lines) == 8, p.stdout + p.stderr
    assert all(ln.startswith("mpiexec -n 3 bin/signorini") for ln in lines)
    assert not os.path.exists(out), "--dry-run created the output directory"


# ---------------------------------------------------------------- real runs

SQUARE = """\
name: square_h
description: square scene, eps = h, max penetration O(h)
options_file: options/square.yaml
options: {contact_monitor: false}
x: h
fit_levels: 3
tolerance: 0.4          # deliberately loose: three coarse levels are pre-asymptotic
norms: [max_penetration, energy]
series:
  - {label: gauss, predicted: {max_penetration: 1.0}}
  - {label: nodal beta=4, options: {penalty_quadrature: nodal, square_beta: 4}}
levels: {key: dm_plex_box_faces, values: ["4,4", "8,8", "16,16"]}
checks:
  - {type: rate, norms: [max_penetration]}
  - {type: monotone, norm: max_penetration}
"""


def test_square_study_end_to_end():
    out = os.path.join(TMP, "square")
    p = cli(write("square.yaml", SQUARE), "--outdir", out, "--check")
    assert p.returncode == 0, f"exit {p.returncode}\n{p.stdout}\n{p.stderr}"
    assert p.stdout.count("bin/signorini") == 6, "the six commands are not printed"
    assert [ln.split()[0] for ln in p.stdout.splitlines() if ln.startswith(("PASS", "FAIL"))] == ["PASS"] * 3
    for f in ("square_h.csv", "square_h.md", "square_h_max_penetration.png", "square_h_energy.png"):
        assert os.path.getsize(os.path.join(out, f)) > 0, f"{f} missing or empty"
    with open(os.path.join(out, "square_h.csv")) as fh:
        rows = list(csv.DictReader(fh))
    assert sorted((r["series"], int(r["level"])) for r in rows) == \
        [(s, k) for s in ("gauss", "nodal beta=4") for k in range(3)], rows
    for r in rows:
        assert r["converged"] == "1" and r["exit_code"] == "0" and float(r["max_penetration"]) > 0
        if r["level"] != "0":  # penetration decreases at a positive rate; energy < 0 has no rate
            assert float(r["rate_max_penetration"]) > 0.3 and r["rate_energy"] == "nan"
    md = open(os.path.join(out, "square_h.md")).read()
    assert "| gauss | max_penetration | 1 |" in md and "| yes |" in md and "nan (e_0 <= 0)" in md


def test_failed_runs_and_rates_fail_the_check():
    text = """\
name: failing
options_file: options/square.yaml
options: {contact_monitor: false}
x: h
norms: [max_penetration]
series: [{label: a, predicted: {max_penetration: 5}}]
levels:
  - {dm_plex_box_faces: "4,4"}
  - {dm_plex_box_faces: "8,8", snes_max_it: 1}
checks: [{type: rate}]
"""
    out = os.path.join(TMP, "failing")
    p = cli(write("failing.yaml", text), "--outdir", out, "--check", "--quiet")
    assert p.returncode == 1, f"exit {p.returncode}\n{p.stdout}\n{p.stderr}"
    assert "bin/signorini" not in p.stdout, "--quiet printed the commands"
    assert "WARNING: series 'a' level 1 FAILED" in p.stderr, p.stderr
    fails = [ln for ln in p.stdout.splitlines() if ln.startswith("FAIL")]
    assert len(fails) == 2 and fails[0].startswith("FAIL converged"), p.stdout
    assert "NOT >= 5 - 0.1" in fails[1], p.stdout
    assert "2 of 2 checks failed" in p.stderr
    with open(os.path.join(out, "failing.csv")) as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["converged"], r["exit_code"]) for r in rows] == [("1", "0"), ("0", "3")], rows


def test_run_without_output_aborts_with_the_solver_output():
    text = """\
name: bogus
options_file: options/square.yaml
x: h
norms: [max_penetration]
series: [{label: a, options: {bogus_option: 1}}]
levels: {key: dm_plex_box_faces, values: ["4,4", "8,8"]}
"""
    p = cli(write("bogus.yaml", text), "--outdir", os.path.join(TMP, "bogus"), "--quiet")
    assert p.returncode == 2, f"exit {p.returncode}\n{p.stderr}"
    assert "series 'a' level 0 exited with status" in p.stderr and "wrote no" in p.stderr, p.stderr
    assert "bogus_option" in p.stderr, "the tail of the solver output is not shown"


def test_missing_norm_attribute_is_an_error_naming_file_and_attribute():
    text = """\
name: noattr
options_file: options/square.yaml
x: h
norms: [no_such_norm]
series: [{label: a}]
levels: {key: dm_plex_box_faces, values: ["2,2", "4,4"]}
"""
    p = cli(write("noattr.yaml", text), "--outdir", os.path.join(TMP, "noattr"), "--quiet")
    assert p.returncode == 2 and "a_0.h5: /run has no attribute 'no_such_norm'" in p.stderr, p.stderr

