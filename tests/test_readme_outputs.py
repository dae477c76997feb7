"""Every output README prints comes from a run of README's own commands, so that it cannot go stale: the block printed
after a command is found, line for line, in what that command prints (the mesh written under tests/out instead of
output/, the output file too). Before, README's options/indenter_accuracy.yaml example said cycle 14 and 78,458
unknowns where the run said cycle 13 and 42,287."""
import os
import re
import subprocess
import sys

from harness import ENV, OUT, ROOT, run


def readme_blocks():
    """(commands, printed lines) of each indented block of README's commands followed by an indented block of output
    (the two separated by one blank line, the commands starting with a program README names)."""
    lines = open(os.path.join(ROOT, "README.md")).read().split("\n")
    blocks, i = [], 0
    while i < len(lines):
        if lines[i].startswith("    ") and re.match(r"    (/usr/bin/python3|bin/signorini|mpiexec)", lines[i]):
            cmds = []
            while i < len(lines) and lines[i].startswith("    "):
                cmds.append(lines[i].strip())
                i += 1
            if i + 1 < len(lines) and lines[i] == "" and lines[i + 1].startswith("    ") and not re.match(r"    (/usr/bin|bin/|mpiexec|make|scene:)", lines[i + 1]):
                printed = []
                i += 1
                while i < len(lines) and lines[i].startswith("    "):
                    printed.append(lines[i][4:])
                    i += 1
                blocks.append((cmds, printed))
            continue
        i += 1
    return blocks


def test_readme_prints_what_its_commands_print(tmp_path):
    blocks = readme_blocks()
    assert blocks, "README prints no output of a command"
    for cmds, printed in blocks:
        mesh = None
        for cmd in cmds:
            words = cmd.split()
            if words[0] == "/usr/bin/python3" and words[1] == "scripts/make_mesh.py":
                i = words.index("-o")
                mesh = str(tmp_path / os.path.basename(words[i + 1]))
                words[i + 1] = mesh
                p = subprocess.run([sys.executable] + words[1:], cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                assert p.returncode == 0, p.stdout
            elif words[0] == "bin/signorini":
                h5 = os.path.join(OUT, "readme.h5")  # after the options file, whose own -output it overrides
                args = words[1:] + (["-dm_plex_filename", mesh] if mesh else []) + ["-output", h5]
                out, _ = run(args, "readme_" + os.path.basename(words[-1]).split(".")[0], output=h5)
                got = [g.strip() for g in out.split("\n")]  # README's block without the summary's indentation
                for line in printed:
                    assert line.strip() in got, f"README prints {line!r}, which `{cmd}` does not:\n{out[-2500:]}"
