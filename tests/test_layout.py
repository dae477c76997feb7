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
