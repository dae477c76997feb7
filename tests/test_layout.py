"""The layout of the sources (make test): no two files of src/ call each other (docs/design.md, "Layout": the arrows run
one way). A file calls another when it calls a function the other defines (a non-static function of its own header);
static inline helpers of the headers belong to no file."""
import glob
import os
import re

from harness import ROOT

DEFINITION = re.compile(r"^(?:PetscErrorCode|void|PetscBool|PetscReal|PetscInt|int|const char \*|PetscScalar)\s+([A-Z][A-Za-z0-9_]*)\s*\(", re.M)


def sources():
    texts = {}
    for path in sorted(glob.glob(os.path.join(ROOT, "src", "**", "*.c"), recursive=True)):
        text = re.sub(r"/\*.*?\*/", "", open(path).read(), flags=re.S)  # comments name functions without calling them
        texts[os.path.relpath(path, ROOT)] = text
    return texts


def call_graph(texts):
    defined = {}
    for path, text in texts.items():
        for name in DEFINITION.findall(text):
            defined.setdefault(name, path)
    calls = {path: set() for path in texts}
    for path, text in texts.items():
        for name, where in defined.items():
            if where != path and re.search(r"\b" + name + r"\s*\(", text):
                calls[path].add(where)
    return defined, calls


def test_no_two_files_call_each_other():
    texts = sources()
    defined, calls = call_graph(texts)
    assert len(texts) > 40 and len(defined) > 150, (len(texts), len(defined))  # the scan found the sources
    cycles = sorted((a, b) for a in calls for b in calls[a] if a < b and a in calls[b])
    assert not cycles, f"files that call each other: {cycles}"


def test_the_check_finds_a_cycle():
    """The check itself: two files made to call each other are found."""
    texts = {"src/a.c": "PetscErrorCode AlphaRun(void)\n{\n  return BetaRun();\n}\n",
             "src/b.c": "PetscErrorCode BetaRun(void)\n{\n  return AlphaRun();\n}\n"}
    _, calls = call_graph(texts)
    assert calls["src/a.c"] == {"src/b.c"} and calls["src/b.c"] == {"src/a.c"}


OPTION_READ = re.compile(r"\bPetscOptions(?:Begin|Get[A-Za-z]*|HasName)\s*\(")
FUNCTION = re.compile(r"^(?:static\s+)?(?:inline\s+)?(?:PetscErrorCode|void|PetscBool|PetscReal|PetscInt|int)\s+\**([A-Za-z_][A-Za-z0-9_]*)\s*\(", re.M)
# The options phase (docs/design.md, "The steps of a run", step 2): each module's options block, the scenes' own
# options (read when the scene is made, before any set-up), the mesh options (MeshCreate) and the checks of src/app/.
OPTIONS_PHASE = re.compile(r"(GetOptions|SetFromOptions|ReadGiven|^SceneCreate_[A-Za-z]+|^MeshCreate|^OptionsCheck[A-Za-z]+|^AppErrorPushHandler|"
                           r"^NameOptionsWithValue)$")


def option_reads(texts):
    """(file, function) of every read of the options database."""
    found = []
    for path, text in texts.items():
        starts = [(m.start(), m.group(1)) for m in FUNCTION.finditer(text)]
        for m in OPTION_READ.finditer(text):
            inside = [name for pos, name in starts if pos < m.start()]
            found.append((path, inside[-1] if inside else "(file scope)"))
    return found


def test_options_are_read_in_the_options_phase_only():
    """No option is read during set-up or solve (issue 30): every PetscOptionsBegin/Get*/HasName of src/ is in a
    function of the options phase."""
    reads = option_reads(sources())
    assert len(reads) > 20, reads  # the scan found them
    outside = sorted({(p, f) for p, f in reads if not OPTIONS_PHASE.search(f)})
    assert not outside, f"options read outside the options phase: {outside}"


def test_the_options_check_finds_a_read_during_the_solve():
    texts = {"src/solver/x.c": "PetscErrorCode SolverStep(SNES snes)\n{\n  PetscCall(PetscOptionsHasName(NULL, NULL, \"-a\", &set));\n}\n",
             "src/solver/y.c": "PetscErrorCode SolverGetOptions(MPI_Comm comm)\n{\n  PetscOptionsBegin(comm, NULL, \"t\", \"\");\n}\n"}
    assert option_reads(texts) == [("src/solver/x.c", "SolverStep"), ("src/solver/y.c", "SolverGetOptions")]


def test_no_code_tests_the_contact_type_by_name():
    """The contact treatment is an object with registered types (include/contact.h): what a type does is asked through
    its operations and flags, never by comparing its name or a method flag outside src/contact/contact.c's registry."""
    texts = sources()
    flag = [p for p, t in texts.items() if re.search(r"method\s*(==|!=)\s*CONTACT_", t)]
    by_name = [p for p, t in texts.items() if p != os.path.join("src", "contact", "contact.c")
               and re.search(r"Str(n)?cmp\([^;]*(CONTACTPENALTY|CONTACTVI|CONTACTNONE|\"penalty\"|\"vi\"|\"none\")", t)]
    assert not flag and not by_name, (flag, by_name)


def folder(path):
    """The folder of src/ a file is in, '' for src/main.c."""
    parts = path.split("/")
    return parts[1] if len(parts) > 2 else ""


def folder_graph(calls):
    """{folder: the other folders its files call}."""
    graph = {}
    for a, targets in calls.items():
        graph.setdefault(folder(a), set()).update(folder(b) for b in targets if folder(b) != folder(a))
    return graph


def folder_cycle(graph):
    """A cycle of folders that call each other (a list, its first folder repeated at its end), or None."""
    state, stack = {}, []

    def visit(f):
        state[f] = 1
        stack.append(f)
        for g in sorted(graph.get(f, ())):
            if state.get(g) == 1:
                return stack[stack.index(g):] + [g]
            if not state.get(g):
                found = visit(g)
                if found:
                    return found
        stack.pop()
        state[f] = 2
        return None

    for f in sorted(graph):
        if not state.get(f):
            found = visit(f)
            if found:
                return found
    return None


def test_no_folder_calls_back_up():
    """The folders of src/ are layers (docs/design.md, "Layout"): no chain of calls leads from a folder back to itself
    (discretization/ and physics/ called each other until the P1 element moved to src/discretization/element_p1.c)."""
    graph = folder_graph(call_graph(sources())[1])
    assert len(graph) >= 10, sorted(graph)
    assert folder_cycle(graph) is None, folder_cycle(graph)


def test_the_folder_check_finds_a_cycle():
    """The check itself: three folders in a ring are found, and a chain is not."""
    assert folder_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert folder_cycle({"a": {"b"}, "b": {"c"}, "c": set()}) is None


def test_design_md_states_the_folders_calls():
    """docs/design.md's list of what each folder calls ("- `X/` calls ...") is the call graph of the sources."""
    text = open(os.path.join(ROOT, "docs", "design.md")).read()
    block = text[text.index("<!-- folder calls -->"):text.index("<!-- end folder calls -->")]
    stated = {}
    for m in re.finditer(r"^- `(\w*)/?` calls (.*)$", block, flags=re.M):
        name = "" if m.group(1) == "main.c" else m.group(1)
        stated[name] = set(re.findall(r"`(\w+)/`", m.group(2)))
    m = re.search(r"^- `main\.c` calls (.*)$", block, flags=re.M)
    stated[""] = set(re.findall(r"`(\w+)/`", m.group(1)))
    graph = folder_graph(call_graph(sources())[1])
    assert stated == graph, {f: (sorted(stated.get(f, ())), sorted(graph.get(f, ()))) for f in set(stated) | set(graph)
                             if stated.get(f) != graph.get(f)}


def test_struct_fields_counts_a_nested_struct():
    """scripts/struct_fields.py matches the braces: a nested anonymous struct is one member of its structure, its own
    members its leaves (the Scene's full_load ended the Scene before, which the script then reported as empty)."""
    import sys
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    import struct_fields as sf
    found = sf.structures("typedef struct {\n  int a;\n  struct { /* } x; */\n    int b, c;\n    double d[3];\n  } inner;\n  PetscReal *e;\n} S;\n")
    assert set(found) == {"S"} and len(sf.members(found["S"])) == 3 and sf.leaves("S", found) == 5, found
    real = sf.structures(sf.headers(None))
    assert "full_load" not in real and any(d == "full_load" for _, d in sf.members(real["Scene"])), sorted(real)


MEASUREMENT = re.compile(r"\d+(\.\d+)?\s*(s|ms|seconds|minutes|GB|MB|kB)\b|\d+(\.\d+)?\s*%|\d+(\.\d+)? times (faster|slower|as long)|\(perf\)", re.I)


def c_comments():
    """(file, line, text) of every C comment of src/ and include/."""
    for path in sorted(glob.glob(os.path.join(ROOT, "src", "**", "*.[ch]"), recursive=True) + glob.glob(os.path.join(ROOT, "include", "*.h"))):
        text = open(path).read()
        for m in re.finditer(r"/\*.*?\*/", text, flags=re.S):
            yield os.path.relpath(path, ROOT), text[:m.start()].count("\n") + 1, m.group(0)


def test_measurements_live_in_docs_not_in_comments():
    """Comments say what the code computes and why (issue 62): at most 5 C comments hold a measurement (seconds, memory,
    a percentage), those stating a bound the code relies on; the others' numbers are in docs/decisions.md, whose
    sections the comments name, each of which exists."""
    found = [(f, line) for f, line, c in c_comments() if MEASUREMENT.search(c)]
    assert len(found) <= 5, found
    headings = set(re.findall(r"^## (.+)$", open(os.path.join(ROOT, "docs", "decisions.md")).read(), flags=re.M))
    named = {(f, name) for f, _, c in c_comments() for name in re.findall(r'docs/decisions\.md,\s+"([^"]+)"', " ".join(c.split()))}
    assert named and all(name in headings for _, name in named), sorted(n for n in named if n[1] not in headings)


def test_design_md_names_every_source_file():
    """docs/design.md's layout names every file of src/ and include/ (issue 62: it named 19 of them before)."""
    text = open(os.path.join(ROOT, "docs", "design.md")).read()
    files = [os.path.basename(p) for p in glob.glob(os.path.join(ROOT, "src", "**", "*.[ch]"), recursive=True) + glob.glob(os.path.join(ROOT, "include", "*.h"))]
    assert len(files) > 90, len(files)
    assert not [f for f in files if f not in text], [f for f in files if f not in text]


def test_petsc_mirrors_are_listed_in_one_table():
    """PETSc 3.18's mirrors in one place (issue 62): docs/decisions.md's table lists at least ten files, each of which
    exists, and each option it names (the comparisons with PETSc's own) is one the solver's sources read."""
    text = open(os.path.join(ROOT, "docs", "decisions.md")).read()
    table = text[text.index("## PETSc 3.18's mirrors"):]
    listed = set(re.findall(r"^\| `(src/[\w/]+\.c)` \|", table, flags=re.M))
    assert len(listed) >= 10, listed
    assert all(os.path.isfile(os.path.join(ROOT, f)) for f in listed), listed
    code = "".join(sources().values())
    options = set(re.findall(r"`(-[a-z_]+)(?: [a-z0-9]+)?`", table))
    assert len(options) >= 8 and all(f'"{opt}"' in code for opt in options), sorted(o for o in options if f'"{o}"' not in code)


CAPABILITY = re.compile(r"\bContact(HasPenalty|HasBounds|HasFrames|IsNone|PointwiseLaw|CanAugment)\s*\(")


def test_the_method_answers_for_itself():
    """Outside src/contact/, code asks the contact method what it is (ContactHasPenalty() and the like) at most 8 times,
    each with a comment on that line or the three before it saying why it cannot be an operation (issue 62: there were
    41; the solver's defaults, the pressure's form and eps are operations of the types now). ContactCanAugment() counts:
    it is the same kind of question."""
    calls = []
    for path in sorted(glob.glob(os.path.join(ROOT, "src", "*", "*.c")) + glob.glob(os.path.join(ROOT, "src", "*.c"))):
        if os.sep + "contact" + os.sep in path:
            continue
        lines = open(path).read().split("\n")
        for i, line in enumerate(lines):
            if CAPABILITY.search(line):
                context = "\n".join(lines[max(0, i - 3):i + 1])
                calls.append((os.path.relpath(path, ROOT), i + 1, "/*" in context))
    assert len(calls) <= 8, calls
    assert all(commented for _, _, commented in calls), [c for c in calls if not c[2]]


APPCTX_FUNCTION = re.compile(r"^(?:static\s+)?(?:inline\s+)?[A-Za-z_][\w \*]*?\b(\w+)\s*\(([^;{}]*?)\)\s*\{", re.M | re.S)


def test_functions_take_what_they_use():
    """At most 25 function definitions take the whole run state AppCtx (issue 62: 135 did; the discretization, the
    physics, the verification, the estimate, the output, the linear acceleration and the Newton core take none now,
    only the drivers of src/drivers/ and src/main.c, where they hand the state on). The layers below the drivers never
    do."""
    takers = []
    for path, text in sources().items():
        for m in APPCTX_FUNCTION.finditer(text):
            if re.search(r"\bAppCtx\b", m.group(2)):
                takers.append((path, m.group(1)))
    assert len(takers) <= 25, takers
    below = [t for t in takers if not (t[0].startswith(os.path.join("src", "drivers")) or t[0] == os.path.join("src", "main.c"))]
    assert not below, below


CALLBACK_SETTERS = re.compile(r"\b(?:SNESSetFunction|SNESSetJacobian|SNESSetConvergenceTest|SNESMonitorSet|SNESSetUpdate|KSPSetPreSolve|KSPSetPostSolve)\s*\(([^;]*)\)\s*\)\s*;")


def function_bodies(text):
    """{name: body} of the functions a file defines (static or not), by matching their braces."""
    bodies = {}
    for m in FUNCTION.finditer(text):
        start = text.find("{", m.end())
        if start < 0 or ";" in text[m.end():start]:
            continue  # a declaration
        depth, i = 0, start
        while i < len(text):
            depth += {"{": 1, "}": -1}.get(text[i], 0)
            if depth == 0:
                break
            i += 1
        bodies[m.group(1)] = text[start:i + 1]
    return bodies


def test_the_core_callbacks_call_nothing_of_linear():
    """The linear acceleration attaches itself to the SNES through PETSc's hooks (docs/design.md, "Layout"): the Newton
    core's callbacks, the functions src/solver/ hands to the SNES and its KSP, and the static functions of their files
    they call, call no function of src/linear/, and src/solver/ sets no KSP pre-solve of its own."""
    texts = sources()
    defined, _ = call_graph(texts)
    linear = {name for name, where in defined.items() if folder(where) == "linear"}
    core = {p: t for p, t in texts.items() if folder(p) == "solver"}
    bodies = {}
    for t in core.values():
        for name, body in function_bodies(t).items():
            bodies.setdefault(name, body)
    callbacks = {n for t in core.values() for m in CALLBACK_SETTERS.finditer(t) for n in re.findall(r"\b[A-Z]\w*\b", m.group(1)) if n in bodies}
    assert {"SolverFormFunction", "SolverFormJacobian", "SolverConverged", "ContactMonitor"} <= callbacks, callbacks
    assert not [p for p, t in core.items() if re.search(r"\bKSPSetPreSolve\s*\(", t)]
    seen, todo, found = set(), sorted(callbacks), []
    while todo:  # the callbacks and what they call inside src/solver/
        name = todo.pop()
        if name in seen or name not in bodies:
            continue
        seen.add(name)
        called = set(re.findall(r"\b([A-Z]\w*)\s*\(", bodies[name]))
        found += [(name, c) for c in sorted(called & linear)]
        todo += sorted(called - linear)
    assert len(seen) >= 6, sorted(seen)  # the walk found the callbacks' bodies
    assert not found, found
