"""README's table "Options the project adds" against `bin/signorini -help` (make test), so that the two cannot drift:
every option of the project that -help prints, in runs that read them all (each scene, each obstacle, 2D and 3D, every
boundary family, GAMG), has a row, and every option of a row is printed by -help, but for the few that -help cannot
show (below, each with its reason)."""
import os
import re

from harness import OUT, ROOT, solve

PROJECT = re.compile(r"^-(contact_|penalty_|bc_|obstacle|scene|young_modulus|poisson_ratio|body_force|partitioner|assembly|output|reference|"
                     r"verify_|perf_|box_|mesh_|section_|square_|patch_|mms_|dual_|mg_fine_|error_|estimate|bars|load_|adapt_|accuracy)")
# the runs whose -help, together, shows every option of the project
RUNS = [
    ["-dm_plex_box_faces", "4,4"],
    ["-dm_plex_box_faces", "4,4", "-scene", "patch"],
    ["-dm_plex_box_faces", "4,4", "-scene", "mms"],
    ["-dm_plex_box_faces", "4,4", "-obstacle", "sphere", "-obstacle_center", "0.5,-2", "-obstacle_radius", "2"],
    ["-dm_plex_dim", "3", "-dm_plex_box_faces", "2,2,2", "-obstacle", "cylinder", "-obstacle_center", "0.5,0.5,-2", "-obstacle_radius", "2",
     "-obstacle_axis", "1,0,0"],
    ["-dm_plex_box_faces", "4,4", "-obstacle", "cone", "-obstacle_point", "0.5,-0.1", "-obstacle_axis", "0,-1", "-obstacle_half_angle", "70.3"],
    ["-dm_plex_box_faces", "4,4", "-obstacle", "punch", "-obstacle_point", "0.5,-0.1", "-obstacle_axis", "0,-1", "-obstacle_radius", "0.2"],
    ["-dm_plex_box_faces", "8,8", "-options_file", "options/solvers/gamg.yaml"],
    ["-scene", "general", "-dm_plex_box_faces", "4,4", "-contact_faces", "1", "-bc_clamp", "3", "-bc_slip", "2", "-bc_slip_2_components", "0",
     "-bc_traction", "4", "-bc_traction_4", "0,0"],
    ["-scene", "general", "-dm_plex_box_faces", "4,4", "-contact_faces", "1", "-bc_clamp", "3", "-bc_pressure", "4", "-bc_pressure_4", "0"],
]
# options of a row that -help does not print, and why
NOT_IN_HELP = {
    "-error_verbose": "read before the options phase, by the error handler (PetscOptionsGetBool prints no help)",
    "-mg_fine_ksp_*": "PETSc's smoother options under the project's prefix, read only when given",
    "-mg_fine_pc_*": "PETSc's smoother options under the project's prefix, read only when given",
}


def readme_rows():
    """The option names of the table's rows (several per row where the row names several), as written: ID for a face
    set, * or ... for a family."""
    text = open(os.path.join(ROOT, "README.md")).read()
    table = text[text.index("## Options the project adds"):]
    table = table[:table.index("\n## ")]
    names = []
    for line in table.splitlines():
        if line.startswith("| `-"):
            first = line.split("|")[1]
            names += [tok.split()[0] for tok in re.findall(r"`(-[^`]+)`", first)]
    return names


def pattern(name):
    """A row's name as a regular expression: ID a face set's number or name, * or a trailing ... any suffix."""
    if name.endswith("*"):
        return re.compile(re.escape(name[:-1]) + r"\w*$")
    return re.compile("^" + re.escape(name).replace("ID", r"[A-Za-z0-9]+") + "$")


def help_options():
    names = set()
    for k, args in enumerate(RUNS):
        rc, text = solve(args + ["-help"], output=os.path.join(OUT, f"readme_help_{k}.h5"))
        assert rc == 0, text[-2000:]
        names |= {m for m in re.findall(r"^\s+(-[a-zA-Z][a-zA-Z0-9_]*)", text, re.M) if PROJECT.match(m)}
    return names


def test_readme_options_table_matches_help(out_root):
    rows = readme_rows()
    assert len(rows) > 40, rows
    # a row "-dual_ksp_type, -dual_pc_type, ..." stands for the family -dual_*
    patterns = [pattern(r) for r in rows] + [pattern("-dual_*")]
    shown = help_options()
    missing = sorted(o for o in shown if not any(p.match(o) for p in patterns))
    assert not missing, f"options -help prints that README's table lacks: {missing}"
    absent = sorted(r for r in rows if r not in NOT_IN_HELP and not any(pattern(r).match(o) for o in shown))
    assert not absent, f"README rows that no -help prints: {absent}"


def test_options_md_is_a_table_of_short_entries_with_the_depth_below():
    """docs/options.md (issue 62): each table cell at most 250 characters, and each entry that says "more below" has
    its section "### `-option`" below the table, in the table's order."""
    text = open(os.path.join(ROOT, "docs", "options.md")).read()
    rows = [line for line in text.split("\n") if line.startswith("| `")]
    assert len(rows) > 60, len(rows)
    long = [(line[:60], len(c.strip())) for line in rows for c in line.strip().strip("|").split("|") if len(c.strip()) > 250]
    assert not long, long
    below = re.findall(r"\(more below, `(-[\w]+)`\)", "\n".join(rows))
    sections = re.findall(r"^### `(-[\w]+)`$", text, flags=re.M)
    assert below and below == sections, (below, sections)


def words_per_sentence(path):
    """The prose of a Markdown page (not its tables, headings or indented blocks): (sentences, words per sentence)."""
    text = open(path).read()
    lines = [line for line in text.split("\n") if line.strip() and not line.startswith(("|", "#", "    "))]
    prose = " ".join(lines)
    sentences = [s for s in re.split(r"(?<=[.!?])\s+(?=[A-Z`(*-])", prose) if s.strip()]
    return len(sentences), len(prose.split()) / max(1, len(sentences))


def test_readme_is_a_short_guide():
    """README is a user's guide read once (issue 62): at most 220 lines, at most 22 words a sentence on average (it had
    235 lines and 36 words a sentence; measured now 220 and about 17)."""
    path = os.path.join(ROOT, "README.md")
    n, wps = words_per_sentence(path)
    assert len(open(path).read().split("\n")) <= 221 and n > 40 and wps <= 22, (n, wps)


def test_docs_speak_of_the_software_not_of_its_sessions():
    """docs/ in the present tense (issue 62): no page speaks of "this session", "the last stop" or an "invocation"."""
    import glob
    found = [(os.path.basename(p), m.group(0)) for p in glob.glob(os.path.join(ROOT, "docs", "*.md"))
             for m in re.finditer(r"this session|last stop|stops before|invocation", open(p).read(), flags=re.I)]
    assert not found, found


def test_design_md_reads_as_prose():
    """docs/design.md at most 25 words a sentence on average (issue 62: it had 43 to 52; measured now about 17)."""
    n, wps = words_per_sentence(os.path.join(ROOT, "docs", "design.md"))
    assert n > 100 and wps <= 25, (n, wps)


def test_running_and_estimate_pages_read_as_prose():
    """docs/running.md and docs/estimate.md at most 25 words a sentence on average (issue 62: they had 52 and 54;
    measured now about 13 and 15)."""
    for name in ("running.md", "estimate.md"):
        n, wps = words_per_sentence(os.path.join(ROOT, "docs", name))
        assert n > 100 and wps <= 25, (name, n, wps)
