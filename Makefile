# Signorini penalty contact solver. `make run` and `make test` install what is missing first.
PYTHON  ?= /usr/bin/python3
MPIEXEC ?= mpiexec
export OMPI_ALLOW_RUN_AS_ROOT = 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM = 1
export OMPI_MCA_rmaps_base_oversubscribe = 1

ifdef PETSC_DIR
  include $(PETSC_DIR)/lib/petsc/conf/variables
  PETSC_CFLAGS = $(PETSC_CC_INCLUDES)
  PETSC_LIBS   = $(PETSC_LIB)
  CC           = $(PCC)
else
  PETSC_CFLAGS = $(shell pkg-config --cflags petsc hdf5-openmpi)
  PETSC_LIBS   = $(shell pkg-config --libs petsc hdf5-openmpi)
  CC           = mpicc
endif
CFLAGS  ?= -O2 -g
CFLAGS  += -std=c99 -Wall -Wextra -Wno-unused-parameter -Werror=implicit-function-declaration -Iinclude -Ibuild
LDLIBS  += $(PETSC_LIBS) -lyaml -lmetis -lm -ldl

SRC = $(wildcard src/*.c src/*/*.c)
OBJ = $(SRC:src/%.c=build/%.o)
BIN = bin/signorini

.PHONY: all deps run test test-long asan rates extremes tradeoff hertz hertz-path penetration-tol incompressible estimates adapt-hertz accuracy-ladder accuracy-ladder-fine hertz-curvature accuracy-remesh work-precision bench format clean
STUDIES = rates2d rates3d epspower2d epsrefine2d
all: $(BIN)

deps:
	@pkg-config --exists petsc && [ -f /usr/include/metis.h ] && [ -f /usr/include/gmshc.h ] && [ -f /usr/include/yaml.h ] && command -v mpicc >/dev/null && command -v mpiexec >/dev/null && command -v pvbatch >/dev/null && \
	  $(PYTHON) -c "import h5py, numpy, matplotlib, yaml, pytest, xdist, gmsh, getfem, dolfinx" 2>/dev/null || sh scripts/install-deps.sh

# -MMD -MP: each object depends on the headers it includes (build/*.d), and only those
build/%.o: src/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -MMD -MP $(PETSC_CFLAGS) -c $< -o $@

# The option names the project reads, for the suggestions of src/app/options_check.c ("did you mean -snes_rtol?")
build/known_options.inc: $(SRC)
	@mkdir -p build
	@grep -ohE '"-[a-z][a-z0-9_]*"' $(SRC) | sort -u | sed 's/$$/,/' > $@
build/flag_options.inc: $(SRC)
	@mkdir -p build
	@grep -ohE 'PetscOptions(Get)?Bool\((NULL, *NULL, *)?"-[a-z][a-z0-9_]*"' $(SRC) | grep -oE '"-[a-z0-9_]+"' | sort -u | sed 's/$$/,/' > $@
build/app/options_check.o build-asan/app/options_check.o: build/known_options.inc build/flag_options.inc

$(BIN): $(OBJ)
	@mkdir -p bin
	$(CC) $(CFLAGS) -o $@ $(OBJ) $(LDLIBS)

# AddressSanitizer and UndefinedBehaviorSanitizer build of the same sources (tests/test_sanitize.py runs a few cases with it)
ASAN_FLAGS = -O1 -g -fsanitize=address,undefined -fno-omit-frame-pointer
ASAN_OBJ   = $(SRC:src/%.c=build-asan/%.o)
ASAN_BIN   = bin/signorini-asan
build-asan/%.o: src/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(ASAN_FLAGS) -MMD -MP $(PETSC_CFLAGS) -c $< -o $@

$(ASAN_BIN): $(ASAN_OBJ)
	@mkdir -p bin
	$(CC) $(CFLAGS) $(ASAN_FLAGS) -o $@ $(ASAN_OBJ) $(LDLIBS)

asan: $(ASAN_BIN)

run: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(MPIEXEC) -n 1 ./$(BIN) -options_file options/square.yaml
	$(PYTHON) scripts/plot_contact.py output/square.h5 -o output/square_contact.png

# The suite runs on as many pytest-xdist workers as cores (TEST_JOBS), each test file on one worker (its module's
# fixtures computed once); TEST_JOBS=0 runs it in the one process. On 2 cores: 8 min against 12.5 (docs/tests.md).
TEST_JOBS ?= $(shell nproc)
test: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) -m pytest -n $(TEST_JOBS) --dist loadfile

# The long tests left out of make test (pytest.ini: -m "not long"): the 2000-draw fuzz run
test-long: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) -m pytest -n $(TEST_JOBS) --dist loadfile -m long

# The paper's convergence studies (docs/verification.md, "Reproducing the paper"): output/studies/<name>/<name>.{csv,md,png}
rates: deps
	@$(MAKE) --no-print-directory $(BIN)
	@for s in $(STUDIES); do $(PYTHON) scripts/study.py options/studies/$$s.yaml --check || exit 1; done

# Stability at the extremes (docs/stability.md); failures of iterative solvers at tiny eps are
# expected and reported in the tables, so extremes_eps runs without --check.
extremes: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/study.py options/studies/extremes_eps.yaml
	$(PYTHON) scripts/study.py options/studies/extremes_material.yaml --check
	$(PYTHON) scripts/study.py options/studies/extremes_loads.yaml --check

# Speed against accuracy (docs/solvers.md, "Choosing eps and the solver"): output/tradeoff/tradeoff/
tradeoff: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/tradeoff.py options/studies/tradeoff.yaml

# Hertz contact against the closed form, 2D and 3D (docs/verification.md, "Hertz contact against the closed form"): output/hertz/hertz.{md,csv}, hertz_<case>.png;
# then the indenters along a load path, with the force-depth curve against the closed form (hertz-path, below)
hertz: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/hertz.py --check 0.01
	$(PYTHON) scripts/hertz_path.py --check 0.01

# Hertz along a load path (docs/hertz.md): the two indenters in 10 steps, a and p0 at every step against the closed form
# at its force, the sphere's force-depth exponent: output/hertz_path/hertz_path.{md,csv,png}
hertz-path: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/hertz_path.py --check 0.01

# -contact_penetration_tol on a ladder of tolerances, eps continuation and the augmented Lagrangian (docs/solvers.md,
# "A penetration tolerance instead of an eps"): the square at 512 x 512
# with GAMG and the 3D sphere indenter, d = 1e-2, 1e-4, 1e-6 h: output/penetration_tol/penetration_tol.{md,csv}
penetration-tol: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/penetration_tol.py

# P1 near incompressibility on make hertz's cylinder against the closed form (bench/incompressible.md, docs/hertz.md)
incompressible: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/incompressible.py --out bench/incompressible.md

# The a posteriori estimate (docs/estimate.md): effectivity on the manufactured solutions, its penalty part against SNESVI,
# the error density on Hertz: output/estimates/estimates.{md,csv}, penalty.csv, hertz.csv, effectivity.png, hertz_density.png
estimates: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/estimates.py --check

# Adaptive refinement (docs/estimate.md, "Adaptive refinement"): the 2D cylinder indenter from a uniform mesh, a and p0
# against the closed form after 0 to 10 cycles: output/adapt_hertz/adapt_hertz.{md,csv}
adapt-hertz: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/adapt_hertz.py

# -accuracy on the 2D Hertz cylinder indenter from a coarse uniform mesh (3% and 1%), against the closed form and
# against make hertz's grading on the same block, timed side by side: output/accuracy_ladder/accuracy_ladder.{md,csv}
accuracy-ladder: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/accuracy_ladder.py

# The ladder's 0.3% rung, on a cylinder of radius 10 (the same a; with radius 1 the closed form itself is 0.25% from the
# model: make hertz-curvature): output/accuracy_ladder_r10/accuracy_ladder.{md,csv} (about 2 minutes, 2.3 GB; one run, timed once)
accuracy-ladder-fine: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/accuracy_ladder.py --tols 0.003 --radius 10 --pairs 0 --no-coverage --outdir output/accuracy_ladder_r10

# How close Hertz's closed form holds on the 2D indenter: its offset against the obstacle's curvature a / R and the
# Poisson ratio (docs/hertz.md): output/hertz_curvature/hertz_curvature.{md,csv}
hertz-curvature: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/hertz_curvature.py

# -accuracy by remeshing the Gmsh model (-adapt_model) on make hertz's elastic cylinder (3%, 1%) and sphere (10%), against
# make hertz's graded meshes, timed side by side: output/accuracy_remesh/accuracy_remesh.{md,csv}
accuracy-remesh: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/accuracy_remesh.py

# Error against unknowns and time (docs/estimate.md, "Adaptive, uniform and hand-graded meshes"): adaptive cycles, uniform
# and hand-graded meshes on the 2D cylinder indenter, the elastic cylinder and the manufactured solution:
# output/work_precision/work_precision.{md,csv} and docs/accuracy_work_precision.png
work-precision: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/work_precision.py

# Performance (docs/solvers.md, "Performance"): bench/{bench,getfem,fenicsx,profile3d,bandwidth,targets}.{md,csv}, runs under bench/runs/
bench: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/bench.py options/bench/bench.yaml
	$(PYTHON) scripts/bench_getfem.py
	$(PYTHON) scripts/bench_fenicsx.py
	$(PYTHON) scripts/profile3d.py
	$(PYTHON) scripts/bench_bandwidth.py
	$(PYTHON) scripts/bench_targets.py

study-%: deps
	@$(MAKE) --no-print-directory $(BIN)
	$(PYTHON) scripts/study.py options/studies/$*.yaml --check

format:
	clang-format -i src/*.c src/*/*.c src/*/*.h include/*.h

clean:
	rm -rf build build-asan bin output tests/out .pytest_cache

-include $(OBJ:.o=.d) $(ASAN_OBJ:.o=.d)
