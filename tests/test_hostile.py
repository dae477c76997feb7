"""Hostile input (make test), the one catalogue of bad input: every case is refused with exit status 2 (a refusal of
the user's input; the one exception, with its reason: the full disk) and a message that names the
option or the file, and leaves the previous good output at the same path byte for byte as it was, with no temporary
file beside it.

Each case runs in a directory of its own holding a copy of a good run's result.h5 and result.xdmf; the bad run is
aimed at result.h5 (or at the hostile -output path of the case, next to it).
"""
import hashlib
import os
import shutil
import stat
import subprocess

import numpy as np
import pytest

from harness import OUT, ROOT, command, refused, run, solve, write_gmsh_cube, write_gmsh_square

HOSTILE = os.path.join(OUT, "hostile")
SMALL = ["-dm_plex_box_faces", "4,4"]


@pytest.fixture(scope="session")
def hostile_dir(out_root):
    """tests/out/hostile, the directory of the hostile cases."""
    os.makedirs(HOSTILE, exist_ok=True)
    return HOSTILE


@pytest.fixture(scope="session")
def good_output(hostile_dir):
    """A good run's FILE.h5 and FILE.xdmf, made once and copied into each case's directory."""
    _, h5 = run(SMALL, "hostile/good")
    return {"h5": h5, "xdmf": h5[:-3] + ".xdmf"}


def digest(path):
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


def snapshot(directory):
    """Every entry of the directory: kind and, for a regular file, its digest (symbolic links are not followed)."""
    state = {}
    for name in sorted(os.listdir(directory)):
        path = os.path.join(directory, name)
        mode = os.lstat(path).st_mode
        if stat.S_ISREG(mode):
            state[name] = ("file", digest(path))
        elif stat.S_ISLNK(mode):
            state[name] = ("link", os.readlink(path))
        else:
            state[name] = ("dir" if stat.S_ISDIR(mode) else "fifo" if stat.S_ISFIFO(mode) else "other", None)
    return state


@pytest.fixture
def case_dir(good_output):
    """case_dir(name): tests/out/hostile/NAME, made anew with a copy of the good output (result.h5, result.xdmf)."""
    def make(name):
        d = os.path.join(HOSTILE, name)
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        shutil.copy2(good_output["h5"], os.path.join(d, "result.h5"))
        shutil.copy2(good_output["xdmf"], os.path.join(d, "result.xdmf"))
        return d
    return make


def refuse(d, args, message, output=None, np_=1, status=2):
    """Runs the bad case in directory d; returns its output. Asserts the exit status, the message, that no temporary
    (.signorini-XXXXXX, src/io/output_file.c) is left and that d is as it was."""
    before = snapshot(d)
    target = output if output is not None else os.path.join(d, "result.h5")
    rc, text = solve(args, np_=np_, output=target, timeout=300)
    cmd = " ".join(command(args, np_, target))
    assert rc == status, f"exit status {rc}, expected {status}: {cmd}\n{text[-2500:]}"
    assert message in text, f"message '{message}' not in:\n{text[-2500:]}"
    after = snapshot(d)
    left = [n for n in after if n.startswith(".signorini-")]
    assert not left, f"temporaries left: {left}"
    assert after == before, f"the directory changed: {before} -> {after}"
    return text


# (name, args, message): options and values. Messages name the option.
OPTION_CASES = [
    ("unknown_scene", ["-scene", "nosuch"], "Unknown scene 'nosuch' (-scene)"),
    ("eps_zero", ["-penalty_eps", 0], "-penalty_eps must be positive"),
    ("eps_negative", ["-penalty_eps", -1e-3], "-penalty_eps must be positive"),
    ("eps_inf", ["-penalty_eps", "inf"], "-penalty_eps must be a finite number"),
    ("eps_nan", ["-penalty_eps", "nan"], "-penalty_eps must be a finite number"),
    ("eps0_inf", ["-penalty_eps0", "inf"], "-penalty_eps0 must be a finite number"),
    ("eps0_zero", ["-penalty_eps0", 0], "-penalty_eps0 must be positive"),
    ("eps0_underflow", ["-penalty_eps0", "1e-320"], "is outside [1e-290, 1e290]: the penalty 1/eps would overflow or vanish"),
    ("eps_overflow", ["-penalty_eps", "1e300"], "is outside [1e-290, 1e290]"),
    ("value_missing", ["-young_modulus", "-penalty_eps0", 1], "option(s) given without a value: -young_modulus"),
    ("value_missing_petsc", ["-snes_rtol"], "option(s) given without a value: -snes_rtol"),
    ("options_file_directory", ["-options_file", "tests"], "-options_file 'tests': the options file is a directory"),
    ("eps_power", ["-penalty_eps_power", 5], "-penalty_eps_power must lie in [0, 4]"),
    ("sweep_inf", ["-penalty_eps0_sweep", "1,inf"], "-penalty_eps0_sweep must be a list of finite numbers, got inf"),
    ("sweep_negative", ["-penalty_eps0_sweep", "1,-1"], "-penalty_eps0_sweep: every value must be positive"),
    ("sweep_with_eps", ["-penalty_eps0_sweep", "1,0.1", "-penalty_eps", 1e-3], "-penalty_eps0_sweep cannot be given together with -penalty_eps"),
    ("sweep_with_vi", ["-penalty_eps0_sweep", "1,0.1", "-contact_method", "vi"], "-penalty_eps0_sweep needs -contact_method penalty"),
    ("young_inf", ["-young_modulus", "inf"], "-young_modulus must be a finite number"),
    ("young_nan", ["-young_modulus", "nan"], "-young_modulus must be a finite number"),
    ("young_zero", ["-young_modulus", 0], "-young_modulus must be positive"),
    ("poisson_half", ["-poisson_ratio", 0.5], "-poisson_ratio must lie in (-1, 0.5)"),
    ("poisson_high", ["-poisson_ratio", 0.7], "-poisson_ratio must lie in (-1, 0.5), got 0.7"),
    ("poisson_nan", ["-poisson_ratio", "nan"], "-poisson_ratio must be a finite number"),
    ("beta_inf", ["-square_beta", "inf"], "-square_beta must be a finite number"),
    ("beta_nan", ["-square_beta", "nan"], "-square_beta must be a finite number"),
    ("x0_inf", ["-square_x0", "-inf"], "-square_x0 must be a finite number"),
    ("tilt_range", ["-square_tilt", 60], "-square_tilt must lie in (-45, 45) degrees"),
    ("mms_amplitude_inf", ["-scene", "mms", "-mms_amplitude_A", "inf"], "-mms_amplitude_A must be a finite number"),
    ("mms_nu_zero", ["-scene", "mms", "-mms_nu", 0], "-mms_nu must lie in (0, 1]"),
    ("mms_a_outside", ["-scene", "mms", "-mms_a", 1.5], "-mms_a must lie in (0, 1)"),
    ("patch_lift_nan", ["-scene", "patch", "-patch_lift", "nan"], "-patch_lift must be a finite number"),
    ("box_upper_inf", ["-dm_plex_box_upper", "inf,1"], "-dm_plex_box_upper must be a list of finite numbers, got inf"),
    ("box_upper_below_lower", ["-dm_plex_box_upper", "0,1"], "-dm_plex_box_upper must exceed -dm_plex_box_lower"),
    ("box_faces_zero", ["-dm_plex_box_faces", "0,4"], "-dm_plex_box_faces: need at least one cell per side"),
    ("box_faces_overflow", ["-dm_plex_box_faces", "100000,100000"], "-dm_plex_box_faces with 0 refinement(s): the mesh would have 2e+10 cells, more mesh points than"),
    ("box_faces_memory", ["-dm_plex_box_faces", "5000,5000"], "the mesh would have 5e+07 cells and need at least 50 GB of memory"),
    ("refine_memory", ["-dm_plex_box_faces", "64,64", "-dm_refine", 10], "-dm_plex_box_faces with 10 refinement(s): the mesh would have"),
    ("grid_sequence_memory", ["-dm_plex_box_faces", "64,64", "-contact_grid_sequence", 8], "-dm_plex_box_faces with 8 refinement(s)"),
    ("grid_sequence_range", ["-contact_grid_sequence", 9], "-contact_grid_sequence must lie in [0, 8]"),
    ("continuation_factor", ["-penalty_continuation_factor", 1.5], "-penalty_continuation_factor must lie in (0, 1)"),
    ("load_rtol", ["-contact_load_rtol", 2], "-contact_load_rtol must lie in [0, 1)"),
    ("ew_guard", ["-contact_ew_guard", 2], "-contact_ew_guard must lie in [0, 1], got 2"),
    ("coarse_levels_range", ["-contact_coarse_levels", -2], "-contact_coarse_levels must lie in [-1, 8] (-1: automatic), got -2"),
    ("coarse_levels_not_divisible", ["-dm_plex_box_faces", "12,20", "-contact_coarse_levels", 3],
     "-contact_coarse_levels 3: -dm_plex_box_faces 12 is not divisible by 2^3"),
    ("coarse_levels_quads", ["-dm_plex_simplex", 0, "-contact_coarse_levels", 1],
     "-contact_coarse_levels 1 needs the simplex box (-dm_plex_box_faces) without -dm_refine"),
    ("coarse_levels_p2", ["-displacement_petscspace_degree", 2, "-contact_coarse_levels", 1],
     "-contact_coarse_levels 1 needs P1 displacements, got -displacement_petscspace_degree 2"),
    ("coarse_rtol", ["-contact_coarse_rtol", 0], "-contact_coarse_rtol must lie in (0, 1), got 0"),
    ("mg_without_nested_meshes", ["-pc_type", "mg", "-contact_coarse_levels", 0],
     "-pc_type mg takes its levels from nested meshes, and this mesh has none"),
    ("mg_p2", ["-pc_type", "mg", "-displacement_petscspace_degree", 2], "-pc_type mg takes its levels from nested meshes, and this mesh has none"),
    ("mg_levels", ["-dm_plex_box_faces", "64,64", "-pc_type", "mg", "-pc_mg_levels", 3],
     "-pc_mg_levels: the levels of -pc_type mg are the nested meshes (-contact_coarse_levels, -contact_grid_sequence)"),
    ("unknown_method", ["-contact_method", "bogus"], "Unknown option bogus for -contact_method"),
    ("unknown_partitioner", ["-partitioner", "bogus"], "Unknown option bogus for -partitioner"),
    ("option_typo", ["-penalty_esp", 1], "never used (misspelled? see -help): -penalty_esp"),
    ("typo_cycle_damping", ["-penalty_eps0", 1, "-contact_cycle_dampng", 0],
     "never used (misspelled? see -help): -contact_cycle_dampng (did you mean -contact_cycle_damping?)"),
    ("vi_with_newtonls", ["-contact_method", "vi", "-snes_type", "newtonls"], "-snes_type newtonls does not fit -contact_method vi"),
    ("vi_with_sbaij", ["-contact_method", "vi", "-dm_mat_type", "sbaij"], "-contact_method vi cannot use the block matrix seqsbaij (-dm_mat_type)"),
    ("vi_with_baij", ["-contact_method", "vi", "-dm_mat_type", "baij"], "-contact_method vi cannot use the block matrix seqbaij (-dm_mat_type)"),
    ("vi_with_gamg", ["-contact_method", "vi", "-pc_type", "gamg"], "-pc_type gamg cannot follow the reduced system"),
    ("vi_with_mg", ["-contact_method", "vi", "-pc_type", "mg"], "-pc_type mg cannot follow the reduced system"),
    ("p1_assembly_on_p2", ["-displacement_petscspace_degree", 2, "-assembly", "p1"], "-assembly p1 needs P1 displacements"),
    # the whole value and the option named: PETSc's reader said "Unknown option plane,cylind" and "Input string 210 GPa has no
    # numeric value", and listed no choice for a misspelled quantity
    ("two_obstacles", ["-obstacle", "plane,cylinder"], "-obstacle plane,cylinder: -obstacle takes one value (one of plane, sphere, cylinder, cone, punch), not a list"),
    ("obstacle_typo", ["-obstacle", "cilinder"], "-obstacle: unknown value 'cilinder' (did you mean cylinder?); the values are plane, sphere, cylinder, cone, punch"),
    ("modulus_with_unit", ["-young_modulus", "210 GPa"], "-young_modulus 210 GPa: Input string 210 GPa has no numeric value"),
    ("quantity_typo", ["-accuracy", 0.1, "-accuracy_quantity", "energy,contact_forse"],
     "-accuracy_quantity: unknown value 'contact_forse' (did you mean contact_force?); the values are energy, contact_force, pressure_max"),
]
@pytest.mark.parametrize("name,args,message", OPTION_CASES, ids=[c[0] for c in OPTION_CASES])
def test_hostile_option(case_dir, name, args, message):
    refuse(case_dir(name), SMALL + args, message)


def test_hostile_parallel_runs_refuse_alike(case_dir):
    """On 2 ranks too: an infinite modulus and a missing mesh are named, and the output is left alone."""
    refuse(case_dir("parallel_young_inf"), SMALL + ["-young_modulus", "inf"], "-young_modulus must be a finite number", np_=2)
    d = case_dir("parallel_missing_mesh")
    refuse(d, ["-dm_plex_filename", os.path.join(d, "missing.msh")], f"Mesh file '{os.path.join(d, 'missing.msh')}' (-dm_plex_filename) does not exist", np_=2)


# ---------------------------------------------------------------- files: every message names the file
def write_text(text):
    def writer(path):
        with open(path, "w") as fh:
            fh.write(text)
    return writer


def write_truncated_mesh(path):
    write_gmsh_square(path, 4)
    text = open(path).read()
    with open(path, "w") as fh:
        fh.write(text[: len(text) // 2])


# (name, file name, writer of the file (None: the file is missing), options given the path, message given the path)
FILE_CASES = [
    ("missing_mesh", "missing.msh", None, lambda f: ["-dm_plex_filename", f],
     lambda f: f"Mesh file '{f}' (-dm_plex_filename) does not exist or cannot be read"),
    ("truncated_mesh", "truncated.msh", write_truncated_mesh, lambda f: ["-dm_plex_filename", f],
     lambda f: f"Cannot read the mesh file '{f}' (-dm_plex_filename): "),
    ("garbage_mesh", "garbage.msh", write_text("garbage\n"), lambda f: ["-dm_plex_filename", f],
     lambda f: f"Cannot read the mesh file '{f}' (-dm_plex_filename): File is not a valid Gmsh file"),
    ("no_contact", "no_contact.msh", lambda f: write_gmsh_square(f, 4, with_contact=False), lambda f: ["-dm_plex_filename", f],
     lambda f: 'The mesh has no contact boundary: no face carries "Face Sets" value 1 (Gamma_C)'),
    # a Gmsh mesh with no face of Gamma_D was a DIVERGED_LINEAR_SOLVE; now it is refused before the solve
    ("no_clamp", "no_clamp.msh", lambda f: write_gmsh_square(f, 4, with_clamp=False), lambda f: ["-dm_plex_filename", f],
     lambda f: '-bc_clamp 3: no face of the mesh carries "Face Sets" value 3 (scene square)'),
    ("tets_dim2", "cube.msh", lambda f: write_gmsh_cube(f, 2), lambda f: ["-dm_plex_filename", f, "-dm_plex_dim", 2],
     lambda f: f"The mesh file '{f}' holds a 3D mesh, but -dm_plex_dim 2 was given"),
    ("missing_options", "missing.yaml", None, lambda f: ["-options_file", f],
     lambda f: f"signorini: error: -options_file '{f}': the options file cannot be opened (No such file or directory)"),
    ("malformed_yaml", "malformed.yaml", write_text("scene: square\n  bad: [unclosed\n"), lambda f: ["-options_file", f],
     lambda f: f"the options file '{f}' is not valid YAML: mapping values are not allowed in this context at line 2"),
    # PETSc kept the second value of a key given twice without a word
    ("yaml_key_twice", "twice.yaml", write_text("scene: square\nyoung_modulus: 2\npoisson_ratio: 0.3\nyoung_modulus: 3\n"), lambda f: ["-options_file", f],
     lambda f: f"the options file '{f}' gives the key 'young_modulus' twice, at lines 2 and 4"),
]
# the cases also given the file by its path relative to the working directory (the repository root), as typed: the
# file is found, and the message names it as given
RELATIVE = ("missing_mesh", "no_contact", "missing_options")
FILE_PARAMS = ([pytest.param(*c, False, id=c[0]) for c in FILE_CASES] +
               [pytest.param(*c, True, id=c[0] + "_relative") for c in FILE_CASES if c[0] in RELATIVE])
@pytest.mark.parametrize("name,file,writer,args,message,relative", FILE_PARAMS)
def test_hostile_file(case_dir, name, file, writer, args, message, relative):
    d = case_dir(name + ("_relative" if relative else ""))
    path = os.path.join(d, file)
    if writer:
        writer(path)
    given = os.path.relpath(path, ROOT) if relative else path
    refuse(d, args(given), message(given))


def test_hostile_reference_files(case_dir):
    """-reference: missing, not HDF5, of another scene, without its displacement; all refused before the solve."""
    d = case_dir("reference")
    missing, not_h5 = os.path.join(d, "missing.h5"), os.path.join(d, "mesh.msh")
    write_gmsh_square(not_h5, 2)
    refuse(d, SMALL + ["-reference", missing], f"Reference file '{missing}' (-reference) does not exist or cannot be read")
    refuse(d, SMALL + ["-reference", not_h5], f"Reference file '{not_h5}' (-reference) is not an HDF5 file")
    good = os.path.join(d, "result.h5")
    out = refuse(d, SMALL + ["-scene", "mms", "-reference", good], f"Reference {good} is a run of scene square, this is scene mms")
    assert "SNES" not in out, "refused only after the solve"
    import h5py
    crippled = os.path.join(HOSTILE, "crippled_reference.h5")
    shutil.copy2(good, crippled)
    with h5py.File(crippled, "a") as f:
        del f["vertex_fields/displacement"]
    refuse(d, SMALL + ["-reference", crippled], f"Reference file {crippled} has no dataset /vertex_fields/displacement")


# ---------------------------------------------------------------- -output itself
def test_hostile_output_is_a_directory(case_dir):
    d = case_dir("output_dir")
    os.mkdir(os.path.join(d, "adir.h5"))
    out = refuse(d, SMALL, f"-output {d}/adir.h5 is a directory", output=os.path.join(d, "adir.h5"))
    assert "SNES" not in out, "found only after the solve"
    refuse(d, SMALL, f"-output {d}/ names a directory, not a file", output=d + "/")


# (name, what to make in the case's directory d, the -output path, the message), all as functions of d; what was
# made (a FIFO, a link to the good output, a directory) must be left as it was
OUTPUT_CASES = [
    ("output_fifo", lambda d: os.mkfifo(os.path.join(d, "fifo.h5")), lambda d: os.path.join(d, "fifo.h5"),
     lambda d: f"-output {d}/fifo.h5 is a FIFO"),
    ("output_link", lambda d: os.symlink("result.h5", os.path.join(d, "link.h5")), lambda d: os.path.join(d, "link.h5"),
     lambda d: f"-output {d}/link.h5 is a symbolic link"),
    ("output_xdmf_dir", lambda d: os.mkdir(os.path.join(d, "other.xdmf")), lambda d: os.path.join(d, "other.h5"),
     lambda d: f"The XDMF file of -output {d}/other.h5, {d}/other.xdmf, is a directory"),
    ("output_nodir", lambda d: None, lambda d: os.path.join(d, "nope", "x.h5"),
     lambda d: f"Output directory '{d}/nope' (-output {d}/nope/x.h5) does not exist or is not writable"),
    ("output_in_a_file", lambda d: None, lambda d: os.path.join(d, "result.h5", "x.h5"),
     lambda d: f"Output directory '{d}/result.h5' (-output {d}/result.h5/x.h5) does not exist or is not writable"),
]
@pytest.mark.parametrize("name,make,output,message", OUTPUT_CASES, ids=[c[0] for c in OUTPUT_CASES])
def test_hostile_output(case_dir, name, make, output, message):
    d = case_dir(name)
    make(d)
    refuse(d, SMALL, message(d), output=output(d))


def test_hostile_output_names_too_long(case_dir):
    """A name the file system refuses (256 characters), and a 255-character FILE.h5 whose FILE.xdmf would be 257."""
    d = case_dir("output_long")
    refuse(d, SMALL, "has 259 characters, more than the 255 the file system", output=os.path.join(d, "a" * 256 + ".h5"))
    refuse(d, SMALL, "-output: the XDMF file beside it", output=os.path.join(d, "b" * 252 + ".h5"))


@pytest.mark.parametrize("sharedfp", ["default", "lockedfile", "individual"])
def test_hostile_disk_full(case_dir, good_output, sharedfp, monkeypatch):
    """A full file system (a 96 kB tmpfs holding a good 4x4 output) during the write: one sentence naming the file and
    the cause, the good output untouched, no temporary left. Also with each of Open MPI's shared file pointers that
    keep files of their own beside the file MPI-IO opens (a lock file, or a data and a metadata file), which a write
    that fails leaves unless the solver removes them (src/io/output_file.c): Open MPI takes one of them where its
    default, "sm", cannot serve (the suite once met it so, beside another run)."""
    if sharedfp != "default":
        monkeypatch.setenv("OMPI_MCA_sharedfp", sharedfp)
    d = case_dir("disk_full_" + sharedfp)
    small = os.path.join(d, "small")
    os.mkdir(small)
    p = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=96k", "tmpfs", small], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert p.returncode == 0, f"cannot mount a small tmpfs for the disk-full test (the test suite runs as root): {p.stdout}"
    try:
        good = good_output
        shutil.copy2(good["h5"], os.path.join(small, "result.h5"))
        shutil.copy2(good["xdmf"], os.path.join(small, "result.xdmf"))
        target = os.path.join(small, "result.h5")
        # exit status 67 (PETSC_ERR_FILE_WRITE), not 2: a full disk is no refusal of the user's input, and gets PETSc's
        # error block with the sentence (src/app/errors.c)
        out = refuse(small, ["-dm_plex_box_faces", "24,24"], f"Cannot write the output file {target}: no space left on the device of '{small}'", output=target,
                     status=67)
        assert "H5Dcreate2" not in out and "H5Dwrite" not in out, "raw HDF5 trace"
    finally:
        subprocess.run(["umount", small], check=True)


# ---------------------------------------------------------------- limits that used to crash or truncate
def test_long_output_file_name_is_written(hostile_dir):
    """A 240-character file name crashed Open MPI's MPI-IO ("buffer overflow detected"); the solver now writes it."""
    name = "c" * 237 + ".h5"
    _, h5 = run(SMALL, "hostile/" + name)
    assert os.path.getsize(h5) > 0 and os.path.getsize(h5[:-3] + ".xdmf") > 0
    assert not [n for n in os.listdir(HOSTILE) if n.startswith(".signorini-")]


def test_long_paths_are_read_and_written(hostile_dir):
    """A 250-character directory: a reference written there, read back by -reference, and a run written there, on 2
    ranks (reading a long path crashed in Open MPI's MPI-IO as writing did)."""
    from harness import load
    long_dir = os.path.join(HOSTILE, "d" * 120, "e" * 120)
    os.makedirs(long_dir, exist_ok=True)
    ref, out = os.path.join(long_dir, "ref.h5"), os.path.join(long_dir, "run.h5")
    run(["-dm_plex_box_faces", "16,16", "-contact_method", "vi"], None, output=ref)
    a, _ = load(run(["-dm_plex_box_faces", "8,8", "-reference", ref], None, np_=2, output=out)[1])
    assert a["converged"] == 1 and a["nprocs"] == 2 and 0.0 < a["reference_error_h1"] < 1.0, a.get("reference_error_h1")


def test_hostile_long_hdf5_mesh_path(case_dir):
    """PETSc reads an HDF5 mesh with MPI-IO itself, where the name cannot be shortened: a name over 240 characters is
    refused with the reason instead of the crash."""
    d = case_dir("long_h5_mesh")
    long_dir = os.path.join(d, "f" * 120, "g" * 120)
    os.makedirs(long_dir)
    mesh = os.path.join(long_dir, "mesh.h5")
    open(mesh, "w").close()
    refuse(d, ["-dm_plex_filename", mesh], f"The HDF5 mesh file name '{mesh}' (-dm_plex_filename) has {len(mesh)} characters")


def test_eps_sweep_of_any_length(hostile_dir):
    """40 values (the sweep used to drop all past the 32nd silently): 40 solves, and the output is the 40th value's."""
    import h5py
    values = [10.0 ** (-k / 8.0) for k in range(40)]
    _, h5 = run(["-dm_plex_box_faces", "8,8", "-penalty_eps0_sweep", ",".join(f"{v:.17g}" for v in values)], "hostile/sweep40")
    with h5py.File(h5, "r") as f:
        eps = f["solves/eps"][:]
        assert f["run"].attrs["n_solves"] == 40 and len(eps) == 40 and f["run"].attrs["converged"] == 1
        h = f["run"].attrs["h"]
        assert abs(f["run"].attrs["eps"] - values[-1] * h) <= 1e-12 * values[-1] * h
        assert abs(eps[-1] - values[-1] * h) <= 1e-12 * values[-1] * h


def test_condition_estimate_with_vi_is_that_of_k(hostile_dir):
    """With SNESVI the estimate used to fail after converging ("Cannot change local size of Amat"); it is the estimate
    of K, the same number as the elastic run's (whose Jacobian is K)."""
    from harness import load
    a_vi, _ = load(run(SMALL + ["-contact_method", "vi", "-contact_condition_estimate"], "hostile/cond_vi")[1])
    a_none, _ = load(run(SMALL + ["-contact_method", "none", "-contact_condition_estimate"], "hostile/cond_none")[1])
    assert a_vi["converged"] == 1 and a_vi["condition_1norm"] > 1.0
    assert abs(a_vi["condition_1norm"] - a_none["condition_1norm"]) <= 1e-8 * a_none["condition_1norm"]


def test_stop_with_a_large_residual_is_a_failure(hostile_dir):
    """PETSc's step-length test (-snes_stol) stops Newton with CONVERGED_SNORM_RELATIVE far from the solution: the run
    reports it as a failure (exit 3, converged = 0), never as a converged result."""
    from harness import load
    out, h5 = run(["-dm_plex_box_faces", "32,32", "-penalty_eps0", 1e-6, "-penalty_continuation", "false", "-snes_stol", 0.9], "hostile/stol", expect_rc=3)
    a, _ = load(h5)
    assert a["snes_reason"] == "CONVERGED_SNORM_RELATIVE" and a["converged"] == 0 and a["residual_reduced"] == 0, (a["snes_reason"], a["converged"])
    assert a["residual_norm"] > 1e-8 * a["load_norm"]
    assert "ERROR: the nonlinear solve failed: it stopped with CONVERGED_SNORM_RELATIVE" in out


# ---------------------------------------------------------------- meshes and face sets the discretization cannot handle
# (issue 29: each was accepted and solved into a wrong answer, |u| = 6e78 on a mixed mesh, a net force from a pressure
# on a line inside the body; now refused before anything is assembled)
GENERAL = ["-scene", "general", "-contact_faces", "bottom", "-bc_clamp", "left"]
MESH_CASES = [
    ("mixed_cells", "write_mixed", [], "mixes cell types ("),
    ("second_order", "write_second_order", [], "holds high-order (curved) elements"),
    ("duplicate_cell", "write_duplicate_cell", ["-contact_faces", "1", "-bc_clamp", "3"], "has 1 duplicate cell(s)"),
    ("interior_pressure", "write_interior_group", ["-bc_pressure", "inner", "-bc_pressure_inner", 0.1],
     "-bc_pressure inner: 2 face(s) of face set 7 are interior faces"),
    ("interior_traction", "write_interior_group", ["-bc_traction", "inner", "-bc_traction_inner", "0,1"],
     "-bc_traction inner: 2 face(s) of face set 7 are interior faces"),
    ("interior_slip", "write_interior_group", ["-bc_slip", "inner", "-bc_slip_inner_components", 0],
     "-bc_slip inner: 2 face(s) of face set 7 are interior faces"),
    ("interior_clamp", "write_interior_group", ["-bc_clamp", "left,inner"], "-bc_clamp inner: 2 face(s) of face set 7 are interior faces"),
    ("interior_contact", "write_interior_group", ["-contact_faces", "bottom,inner"], "-contact_faces inner: 2 face(s) of face set 7 are interior"),
]
@pytest.mark.parametrize("np_", (1, 2))
@pytest.mark.parametrize("name,writer,args,message", MESH_CASES, ids=[c[0] for c in MESH_CASES])
def test_hostile_mesh(case_dir, name, writer, args, message, np_):
    """Refused on 1 and 2 ranks (on 2 the interior faces may lie on the cut between the ranks, one cell on each)."""
    import hostile_meshes
    d = case_dir(f"{name}_{np_}")
    mesh = os.path.join(d, name + ".msh")
    getattr(hostile_meshes, writer)(mesh)
    out = refuse(d, GENERAL + ["-dm_plex_filename", mesh] + args, message, np_=np_)
    if "mesh file" in message or "cell" in message:
        assert mesh in out, "the message does not name the file"


# ---------------------------------------------------------------- errors a user can read (issue 29)
READABLE_CASES = [
    ("young_inf", SMALL + ["-young_modulus", "inf"], "signorini: error: -young_modulus must be a finite number, got inf"),
    ("value_not_a_number", ["-scene", "general", "-contact_faces", 1, "-bc_clamp", 4, "-bc_pressure", 3, "-bc_pressure_3", "1,2"],
     "signorini: error: -bc_pressure_3 1,2: Input string 1,2 has no numeric value"),
    ("value_in_a_list", ["-obstacle", "sphere", "-dm_plex_dim", 3, "-obstacle_center", "1e4.5,0,0", "-obstacle_radius", 1],
     "signorini: error: -obstacle_center 1e4.5: Input string 1e4.5 has no numeric value"),
    ("not_a_bool", SMALL + ["-contact_pc_reuse", "maybe"], "signorini: error: -contact_pc_reuse maybe: Unknown logical value: maybe"),
    ("unknown_choice", SMALL + ["-contact_method", "bogus"], "signorini: error: Unknown option bogus for -contact_method"),
    ("typo_suggestion", ["-dm_plex_box_faces", "64,64", "-snes_rtoll", 1e-9], "never used (misspelled? see -help): -snes_rtoll (did you mean -snes_rtol?)"),
    ("typo_project_option", SMALL + ["-penalty_esp0", 1], "-penalty_esp0 (did you mean -penalty_eps0?)"),
]
@pytest.mark.parametrize("np_", (1, 2))
@pytest.mark.parametrize("name,args,message", READABLE_CASES, ids=[c[0] for c in READABLE_CASES])
def test_refusal_is_one_paragraph(case_dir, name, args, message, np_):
    """A refusal of the input is one paragraph naming the option (and the nearest known option for a misspelling),
    exit status 2, before the solve, without PETSc's error block or its list of "options not used" (which listed the
    valid options of the run as if they were typos); once, on 2 ranks too."""
    text = refuse(case_dir(f"readable_{name}_{np_}"), args, message, np_=np_)  # exit status 2, the directory as it was
    assert text.count("signorini: error:") == 1, text
    for noise in ("PETSC ERROR", "Option left", "were not used", "Configure options", "MPI_ABORT"):
        assert noise not in text, f"'{noise}' in:\n{text[-2000:]}"
    assert "  SNES " not in text, "refused only after the solve"


def test_error_verbose_gives_petsc_report(case_dir):
    """-error_verbose: PETSc's whole error block, with the stack, for a refusal too."""
    d = case_dir("error_verbose")
    rc, text = solve(SMALL + ["-young_modulus", "inf", "-error_verbose"], output=os.path.join(d, "result.h5"), timeout=300)
    assert rc != 0 and "PETSC ERROR: -young_modulus must be a finite number" in text and "ElasticityGetOptions() at" in text, text


def test_options_read_during_the_solve_are_not_refused_early(hostile_dir):
    """The early check leaves the options PETSc reads during the solve (viewers, the levels of a multigrid) to the check
    at the end: a run with them converges, and a misspelled one of them is still refused at the end."""
    args = ["-dm_plex_box_faces", "16,16", "-options_file", "options/solvers/gamg.yaml", "-ksp_view", "ascii:/dev/null", "-mg_levels_ksp_max_it", 2]
    out, _ = run(args, "hostile/read_late")
    assert "  SNES CONVERGED" in out
    out, _ = run(args + ["-mg_levels_ksp_typo", 1], "hostile/read_late_typo", expect_rc=2)
    assert "-mg_levels_ksp_typo (did you mean -mg_levels_ksp_type?)" in out


def test_reference_of_another_problem_is_refused(case_dir):
    """-reference compares a fingerprint of the problem (scene, material, boundary families and values, loads, obstacle),
    not only the mesh (issue 29: a general problem with another load on the same mesh was accepted and compared); the
    method and eps may differ (that is what a reference is for)."""
    d = case_dir("reference_problem")
    general = ["-scene", "general", "-dm_plex_box_faces", "8,8", "-contact_faces", 1, "-bc_clamp", 3]
    ref = os.path.join(d, "ref.h5")
    run(general + ["-bc_clamp_3_translate", "0,-0.01", "-contact_method", "vi"], None, output=ref)
    refuse(d, general + ["-bc_clamp_3_translate", "0,-0.02", "-reference", ref],
           "solved another problem: it has 'clamp 3 value=0,-0.01' where this run has 'clamp 3 value=0,-0.02'")
    refuse(d, general + ["-bc_clamp_3_translate", "0,-0.01", "-young_modulus", 2, "-reference", ref],
           "solved another problem: it has 'E 1' where this run has 'E 2'")
    refuse(d, general + ["-bc_clamp_3_translate", "0,-0.01", "-obstacle_point", "0,-0.001", "-reference", ref], "solved another problem")
    from harness import load
    a, _ = load(run(general + ["-bc_clamp_3_translate", "0,-0.01", "-reference", ref], "hostile/reference_same_problem")[1])
    assert a["converged"] == 1 and 0.0 < a["reference_error_h1"] < 1e-2


def test_tolerance_below_round_off_ends_converged_at_round_off(hostile_dir):
    """eps = 1e-9 far below h/E with -snes_rtol 1e-12 (issue 29): Newton stalled at the round-off of the penalty term
    ((1/eps) times the displacement times the machine epsilon) and ran 57 steps to DIVERGED_MAX_IT. It now stops where a
    step no longer halves |F| near that round-off: converged, /run stopped_at_roundoff = 1, the answer of a run to
    -snes_rtol 1e-8 (which does not stop there)."""
    from harness import load
    args = ["-scene", "general", "-dm_plex_box_faces", "32,32", "-contact_faces", 1, "-bc_clamp", 3, "-bc_clamp_3_translate", "0,-0.02",
            "-obstacle", "cylinder", "-obstacle_center", "0.5,-1", "-obstacle_radius", 1, "-young_modulus", 3, "-penalty_quadrature", "nodal",
            "-penalty_eps", 1e-9]
    out, h5 = run(args + ["-snes_rtol", 1e-12], "hostile/roundoff")
    a, f = load(h5)
    assert a["converged"] == 1 and a["stopped_at_roundoff"] == 1 and a["newton_its"] < 20 and "stopped at round-off" in out
    b, g = load(run(args + ["-snes_rtol", 1e-8], "hostile/roundoff_ref")[1])
    assert b["converged"] == 1 and b["stopped_at_roundoff"] == 0
    assert abs(a["contact_force"] / b["contact_force"] - 1) < 1e-8
    assert np.abs(f["displacement"] - g["displacement"]).max() <= 1e-8 * np.abs(g["displacement"]).max()


def test_a_missing_file_given_by_a_relative_path_says_where_it_was_looked_for(case_dir):
    """A relative path in an options file is taken from the working directory, as PETSc takes every path: the refusal
    says so, naming the directory (before, it named the path alone, and a mesh kept beside its options file seemed lost)."""
    d = case_dir("relative_in_options")
    opts = os.path.join(d, "problem.yaml")
    with open(opts, "w") as fh:
        fh.write("scene: square\ndm_plex_filename: beside_the_options.msh\n")
    refused(["-options_file", opts], "relative_in_options",
            f"Mesh file 'beside_the_options.msh' (-dm_plex_filename) does not exist or cannot be read (a relative path, taken from the working directory {ROOT}")


@pytest.mark.parametrize("np_", [1, 2])
def test_a_later_obstacle_overrides_an_options_file_s(case_dir, np_):
    """Later options override earlier ones, the obstacle's type too: an options file with a cylinder (-obstacle_center,
    -obstacle_radius) and -obstacle plane after it on the command line solve the plane, the file's cylinder options
    named in one line as ignored, and give the answer of a file without them (before, the cylinder's options were
    refused as never used). A misspelled option is still refused, and so are another type's option on the command
    line itself (tests/test_boundary.py: -obstacle plane -obstacle_radius 1) and a name no obstacle type reads in 2D
    (-obstacle_axis)."""
    from harness import load
    d = case_dir(f"obstacle_override_np{np_}")
    common = "scene: general\ndm_plex_box_faces: 8,8\ncontact_faces: 1\nbc_clamp: 3\nbc_clamp_3_translate: 0,-0.01\n"
    with open(os.path.join(d, "cylinder.yaml"), "w") as fh:
        fh.write(common + "obstacle: cylinder\nobstacle_center: 0.5,-1\nobstacle_radius: 1\n")
    with open(os.path.join(d, "plain.yaml"), "w") as fh:
        fh.write(common)
    plane = ["-obstacle", "plane", "-obstacle_point", "0,-0.002", "-obstacle_normal", "0,-1"]
    out, h5 = run(["-options_file", os.path.join(d, "cylinder.yaml")] + plane, f"hostile/obstacle_override_np{np_}", np_=np_)
    assert out.count("note: -obstacle plane does not use -obstacle_center -obstacle_radius") == 1, out
    a, f = load(h5)
    b, g = load(run(["-options_file", os.path.join(d, "plain.yaml")] + plane, f"hostile/obstacle_override_plain_np{np_}", np_=np_)[1])
    assert a["obstacle"] == b["obstacle"] == "plane" and a["contact_force"] > 0, (a["obstacle"], a["contact_force"])
    assert a["contact_force"] == b["contact_force"] and np.array_equal(f["displacement"], g["displacement"])
    refused(["-options_file", os.path.join(d, "cylinder.yaml")] + plane + ["-obstacle_centre", "0,0"], f"obstacle_override_typo_np{np_}",
            "never used (misspelled, or for a face set or obstacle not in use? see -help): -obstacle_centre (did you mean -obstacle_center?)", np_=np_)
    refused(["-options_file", os.path.join(d, "cylinder.yaml"), "-obstacle_axis", "0,1"], f"obstacle_override_axis_np{np_}",
            "never used (misspelled, or for a face set or obstacle not in use? see -help): -obstacle_axis", np_=np_)
