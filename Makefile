# hairbench — the front door. `make help` lists the targets.
#
#   make          build build/hairsim-cpu and, where nvcc is present, the CUDA binaries
#   make test     build (with build/planted/, the judge's planted defects), then run the pytest suite
#                 (GPU tests skip with a reason without a GPU)
#   make bench    build, validate the GPU variants against the CPU, sweep, studies, report (results/local/);
#                 SCENE=my.toml: the same on your own scene or groom (results/scene-my/)
#   make report   re-render a run folder's report (the committed one: REPORT_FROM=results/reference-h200 REPORT_TO=report)

SHELL := /bin/bash
CC      ?= gcc
NVCC    ?= nvcc
PYTHON  ?= python3
# CUDA_ARCH: the GPU architectures the CUDA binaries are built for (docs/cuda.md, "Building for
# your GPU"). Given (CUDA_ARCH=sm_86 or a list, CUDA_ARCH="sm_80 sm_90": one fat binary), else
# those of the GPUs nvidia-smi finds here, else sm_90 (no GPU: CI's compile stays one
# architecture). Worked out once, only when a CUDA rule needs it.
NVIDIA_SMI ?= nvidia-smi
GPU_ARCHS = $(addprefix sm_,$(shell $(NVIDIA_SMI) --query-gpu=compute_cap --format=csv,noheader 2>/dev/null | \
              tr -d ' .' | grep -E '^[0-9]+$$' | sort -un))
ifeq ($(origin CUDA_ARCH),undefined)
  CUDA_ARCH = $(eval CUDA_ARCH := $(or $(strip $(GPU_ARCHS)),sm_90))$(CUDA_ARCH)
endif
# CUDA_DEVICE_OPT: full (the default) optimises the device code as a GPU runs it; check compiles
# every CUDA source through every phase (cicc, ptxas) without optimising it, about 3× faster, for
# a machine with no GPU that needs the sources to compile and nothing to run (CI). The binaries so
# built refuse a GPU. A change of it rebuilds the CUDA objects.
CUDA_DEVICE_OPT ?= full
ifeq ($(filter full check,$(CUDA_DEVICE_OPT)),)
  $(error CUDA_DEVICE_OPT is '$(CUDA_DEVICE_OPT)': give full or check)
endif
BUILD   := build
OBJ     := $(BUILD)/obj

# ---- HDF5: pkg-config first, then h5cc, then Debian's serial layout ----
HDF5_CFLAGS ?= $(shell pkg-config --cflags hdf5 2>/dev/null)
HDF5_LIBS   ?= $(shell pkg-config --libs hdf5 2>/dev/null)
ifeq ($(strip $(HDF5_LIBS)),)
  H5CC_SHOW := $(shell h5cc -show 2>/dev/null)
  HDF5_CFLAGS := $(filter -I%,$(H5CC_SHOW))
  HDF5_LIBS := $(filter -L%,$(H5CC_SHOW)) -lhdf5
endif

# The revision compiled into every output: a REVISION file when one is present (written
# beside a tree copied to a GPU node, whose own .git, if any, can be stale: one was seen at
# an older commit), else git (with -dirty for uncommitted changes to the sources).
REVISION_FILE := $(strip $(shell cat REVISION 2>/dev/null))
IN_GIT := $(shell git rev-parse --is-inside-work-tree 2>/dev/null)
ifneq ($(REVISION_FILE),)
  GIT_REV := $(REVISION_FILE) (REVISION file)
else ifeq ($(IN_GIT),true)
  GIT_REV := $(shell git rev-parse --short=12 HEAD 2>/dev/null || echo unknown)$(shell git diff --quiet HEAD -- c_ref cuda Makefile 2>/dev/null || echo -dirty)
else
  GIT_REV := unknown
endif
# stamp FILE,VALUE: FILE holds VALUE and is rewritten only when VALUE changes, so what depends on
# FILE is rebuilt exactly then
stamp = $(shell mkdir -p $(BUILD) && { [ "$$(cat $(1) 2>/dev/null)" = '$(2)' ] || printf '%s\n' '$(2)' > $(1); })
# record.c compiles GIT_REV in: a commit or a new REVISION rebuilds record.o and relinks the
# binaries instead of keeping an old revision
REV_STAMP := $(BUILD)/revision.stamp
$(call stamp,$(REV_STAMP),$(GIT_REV))
# the CUDA objects depend on CUDA_DEVICE_OPT
DEVICE_OPT_STAMP := $(BUILD)/cuda-device-opt.stamp
$(call stamp,$(DEVICE_OPT_STAMP),$(CUDA_DEVICE_OPT))

# The C reference: C11, no fast-math and no FMA contraction, so it is the oracle.
CSTD    := -std=c11 -D_DEFAULT_SOURCE
COPT    ?= -O2 -g
CWARN   := -Wall -Wextra -Wno-unused-parameter
CFLAGS_REF := $(CSTD) $(COPT) -ffp-contract=off -fno-fast-math $(CWARN)
# The simd variant's file only (docs/cpu_simd.md): AVX2 code checked for at run time, glibc's
# vector math, and of -ffast-math's flags only the two that change no value.
SIMD_CFLAGS := -O3 -march=x86-64-v3 -fopenmp-simd -fno-math-errno -fno-trapping-math
# ... and built a second time (c_ref/simd/*_v4.c) for x86-64-v4 with 512-bit vectors, picked at
# run time on a CPU with AVX-512; the record's flags name the build that ran.
SIMD_V4_CFLAGS := -O3 -march=x86-64-v4 -mprefer-vector-width=512 -fopenmp-simd -fno-math-errno -fno-trapping-math
CPU_FLAGS_STR := $(CC) $(CFLAGS_REF) -fopenmp; simd variant (c_ref/simd/) adds: $(SIMD_CFLAGS)
CPU_FLAGS_STR_V4 := $(CC) $(CFLAGS_REF) -fopenmp; simd variant (c_ref/simd/, x86-64-v4 build) adds: $(SIMD_V4_CFLAGS)

# c_ref/, from the top layer down (docs/decisions/code-layout.md): app/ (the program both binaries
# link: the driver, the backend interface, HDF5 states and the JSON record; it knows both models),
# paper/ and dynamic/ (the two models' reference), runtime/ (model-free: command line, input,
# parameters, safe writes), simd/ (the CPU simd variant), and backend_cpu.c (the CPU backend that
# puts them together). Included as "runtime/params.h".
SHARED_SRC := $(wildcard c_ref/app/*.c c_ref/runtime/*.c) c_ref/paper/model_host.c c_ref/dynamic/dynamics_host.c \
              c_ref/dynamic/motion_track.c c_ref/dynamic/dyn_followers.c c_ref/dynamic/dyn_sagfree.c c_ref/dynamic/dyn_lod.c \
              c_ref/dynamic/colliders.c c_ref/dynamic/sdf_mesh.c c_ref/dynamic/hair_grid.c c_ref/dynamic/world_host.c
SHARED_OBJ := $(SHARED_SRC:c_ref/%.c=$(OBJ)/%.o)
CPU_SRC    := c_ref/paper/model.c c_ref/dynamic/dynamics_f32.c c_ref/dynamic/dynamics_f64.c $(wildcard c_ref/simd/*.c) \
              c_ref/dynamic/world_build.c c_ref/backend_cpu.c
CPU_OBJ    := $(CPU_SRC:c_ref/%.c=$(OBJ)/%.o)
C_HEADERS  := $(wildcard c_ref/*/*.h)

# ---- CUDA: three builds of one source; the flags are recorded in every output ----
HAVE_NVCC := $(shell command -v $(NVCC) >/dev/null 2>&1 && echo yes)
# cuda/: the backend (backend_*.cu) and what both models share at the top, the models' kernels in
# paper/ and dynamic/, --draw in draw/; included by their path from cuda/ ("dynamic/model.cuh")
CUDA_SRC  := $(wildcard cuda/*.cu cuda/*/*.cu)
CUDA_HDR  := $(wildcard cuda/*.cuh cuda/*/*.cuh)
# one architecture: -arch=sm_XX (its code and PTX); several: each one's code, and the newest's
# PTX, which a later GPU compiles when it loads the binary
comma := ,
NVCC_ARCH = $(if $(word 2,$(CUDA_ARCH)),$(foreach a,$(CUDA_ARCH),-gencode arch=compute_$(a:sm_%=%)$(comma)code=$(a)) \
              -gencode arch=compute_$(lastword $(CUDA_ARCH:sm_%=%))$(comma)code=compute_$(lastword $(CUDA_ARCH:sm_%=%)),-arch=$(CUDA_ARCH))
# -Xfatbin -compress-all: every object's device code compressed in the binary; by default nvcc left the lanes
# kernel's split objects uncompressed (the normal binary 80 MB against 30 before the split; lanes_grid's fp32
# object 3.4 MB against 0.83 compressed). The code itself is the same.
NVCC_BASE = $(NVCC_ARCH) -O3 -std=c++17 -Ic_ref -lineinfo -Xcompiler -Wall -Xfatbin -compress-all
NVCC_MODE_normal   :=
NVCC_MODE_strict   := --fmad=false -prec-div=true -prec-sqrt=true -ftz=false -DHB_REFERENCE_ARITHMETIC=1
NVCC_MODE_fastmath := --use_fast_math
NVCC_DEVICE_OPT_full  :=
NVCC_DEVICE_OPT_check := -Xcicc -O1 -Xptxas -O0 -DHB_DEVICE_OPT_CHECK=1
NVCC_DEVICE_OPT = $(if $(NVCC_DEVICE_OPT_$(CUDA_DEVICE_OPT)), $(NVCC_DEVICE_OPT_$(CUDA_DEVICE_OPT)))
CUDA_BINS := $(BUILD)/hairsim-cuda $(BUILD)/hairsim-cuda-strict $(BUILD)/hairsim-cuda-fastmath
HOSTCHECK_BINS := $(BUILD)/hostcheck/paper_hostcheck_reference $(BUILD)/hostcheck/paper_hostcheck_free \
                  $(BUILD)/hostcheck/dyn_hostcheck $(BUILD)/hostcheck/post_hostcheck $(BUILD)/hostcheck/lod_hostcheck \
                  $(BUILD)/hostcheck/draw_hostcheck

.PHONY: all cpu planted cuda hostcheck test bench report report-dynamic help clean setup check-python check-hdf5 sanitize sanitize-gpu sanitize-gpu-world fuzz lint lint-py lint-c fmt docs

# The Python that runs the tests and the harness: harness/setup.sh picks it (PYTHON when it has
# the packages, else ./.venv) after installing what is missing, and writes its path here.
PY_FILE := $(BUILD)/python
RUN_PY   = "$$(cat $(PY_FILE))"

all: cpu cuda

cpu: $(BUILD)/hairsim-cpu $(BUILD)/hairsim-cpu-contract

help:
	@echo "make          build build/hairsim-cpu (and the CUDA binaries where nvcc is present)"
	@echo "make test     build and run the pytest suite (GPU tests skip with a reason without a GPU;"
	@echo "             one pytest-xdist worker a core where xdist is installed, TEST_JOBS=N for N)"
	@echo "make bench    validate GPU variants against the CPU, sweep, studies, report into results/local/ (OUT=results/NAME; BUDGET=10m fits the sizes to a time; SHARD=K/N runs a share)"
	@echo "make bench SCENE=my.toml  the throughput sweep, speed/accuracy study, frame budget and stability map on your own scene or groom (results/scene-my/; docs/user_scene.md)"
	@echo "make report   re-render a run folder's report, or one sweep folder's (REPORT_FROM=results/local, REPORT_TO=REPORT_FROM/report;"
	@echo "             the committed one: REPORT_FROM=results/reference-h200 REPORT_TO=report)"
	@echo "make report-dynamic  only the dynamic report of REPORT_FROM into REPORT_TO"
	@echo "make sanitize build the C reference with ASan+UBSan and run the CPU tests under it"
	@echo "make fuzz     libFuzzer over the HAIR groom reader under ASan+UBSan for FUZZ_SECONDS (default 30) from tests/fuzz/corpus/"
	@echo "make sanitize-gpu  compute-sanitizer memcheck + racecheck over every CUDA variant (GPU node)"
	@echo "make sanitize-gpu-world  the same over the grid and the colliders alone (part of sanitize-gpu)"
	@echo "make lint     ruff check, ruff format --check, mypy (lint-py) and clang-format --dry-run (lint-c)"
	@echo "make fmt      ruff format the Python and clang-format -i the C and CUDA sources"
	@echo "make docs     remake docs/harness.md's command and module reference (python3 -m harness docs)"
	@echo "make setup    install what is missing (apt as root/sudo, pip into the project environment .venv); nothing when all is there"
	@echo "make hostcheck  build the CUDA port's host checks (cuda/hostcheck/, run by tests/native)"
	@echo "make build/sdf-sampling  issue #43's SDF benchmark: plain loads against a 3-D texture (part of make cuda; docs/cuda.md)"
	@echo "make planted  build/planted/: the C reference with each planted defect (python -m harness judge)"
	@echo "make clean    remove build/"

check-hdf5:
	@echo '#include <hdf5.h>' | $(CC) $(HDF5_CFLAGS) -E -x c - >/dev/null 2>&1 || { \
	  echo "error: the HDF5 C library is missing (hdf5.h not found): install it, e.g. 'sudo apt-get install libhdf5-dev hdf5-tools'"; exit 1; }

# Set-up: system packages (apt, as root or with sudo) and the Python packages (pip, into the
# project environment .venv, never a system interpreter's) when missing; nothing is installed
# when all are there.
setup:
	@PYTHON="$(PYTHON)" CC="$(CC)" harness/setup.sh $(PY_FILE)

check-python: setup

$(OBJ)/%.o: c_ref/%.c $(C_HEADERS) | check-hdf5
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_REF) -fopenmp -Ic_ref $(HDF5_CFLAGS) -DHB_GIT_REV='"$(GIT_REV)"' -DHB_FLAGS='"$(CPU_FLAGS_STR)"' \
	  -DHB_FLAGS_SIMD_V4='"$(CPU_FLAGS_STR_V4)"' -c $< -o $@

$(OBJ)/simd/%.o: CFLAGS_REF += $(SIMD_CFLAGS)
# the x86-64-v4 build: the v3 file's source under other flags (the later -march wins)
$(OBJ)/simd/%_v4.o: CFLAGS_REF += $(SIMD_V4_CFLAGS)
$(OBJ)/simd/model_simd_v4.o: c_ref/simd/model_simd.c
$(OBJ)/simd/dynamics_simd_v4.o: c_ref/simd/dynamics_simd.c
$(OBJ)/app/record.o: $(REV_STAMP)

$(BUILD)/hairsim-cpu: $(SHARED_OBJ) $(CPU_OBJ)
	$(CC) -fopenmp $^ -o $@ $(HDF5_LIBS) -lm

# The spread build (docs/judge.md): the C reference's model sources with FMA contraction on,
# a legitimate change of arithmetic whose difference from the reference measures how
# sensitive a scene is; the rest of its objects are the reference's.
CONTRACT_FLAGS := $(filter-out -ffp-contract=off,$(CFLAGS_REF)) -ffp-contract=fast -march=x86-64-v3
CONTRACT_SRC := c_ref/paper/model.c c_ref/dynamic/dynamics_f32.c c_ref/dynamic/dynamics_f64.c c_ref/dynamic/dynamics_host.c \
                c_ref/app/record.c
CONTRACT_OBJ := $(CONTRACT_SRC:c_ref/%.c=$(OBJ)/contract/%.o)
$(OBJ)/contract/%.o: c_ref/%.c $(C_HEADERS) | check-hdf5
	@mkdir -p $(dir $@)
	$(CC) $(CONTRACT_FLAGS) -fopenmp -Ic_ref $(HDF5_CFLAGS) -DHB_GIT_REV='"$(GIT_REV)"' \
	  -DHB_FLAGS='"$(CC) $(CONTRACT_FLAGS) -fopenmp (spread build: $(notdir $(CONTRACT_SRC)); the rest as hairsim-cpu)"' -c $< -o $@
$(OBJ)/contract/app/record.o: $(REV_STAMP)
$(BUILD)/hairsim-cpu-contract: $(CONTRACT_OBJ) $(filter-out $(CONTRACT_SRC:c_ref/%.c=$(OBJ)/%.o),$(SHARED_OBJ) $(CPU_OBJ))
	$(CC) -fopenmp $^ -o $@ $(HDF5_LIBS) -lm

# Planted defects (docs/judge.md), test-only: build/planted/hairsim-cpu-plant<n> is the C
# reference with `#if HB_PLANT == n` hunk n compiled in. Not part of `make`; `make planted`.
PLANTS := $(shell grep -ho 'HB_PLANT == [0-9]*' c_ref/*/*.c c_ref/*/*.h | awk '{print $$3}' | sort -un)
PLANT_SRC := c_ref/dynamic/dynamics_f32.c c_ref/dynamic/dynamics_f64.c c_ref/dynamic/dynamics_host.c c_ref/paper/model.c \
             c_ref/dynamic/dyn_lod.c
PLANT_BINS := $(PLANTS:%=$(BUILD)/planted/hairsim-cpu-plant%)
planted: $(PLANT_BINS)
PLANT_CC := $(CC) $(CFLAGS_REF) -Ic_ref -O0 -g0 -fopenmp $(HDF5_CFLAGS)
PLANT_BASE := $(PLANT_SRC:c_ref/%.c=$(BUILD)/planted/base/%.o)
.SECONDARY: $(PLANT_BASE) $(foreach n,$(PLANTS),$(foreach f,$(PLANT_SRC),$(BUILD)/planted/obj$(n)/$(notdir $(f:.c=.o))))
# each source once without a plant (and its preprocessed text): a plant's source whose text that
# plant leaves unchanged links this object, the same bytes as compiling it again
$(BUILD)/planted/base/%.o: c_ref/%.c $(C_HEADERS) | check-hdf5
	@mkdir -p $(@D)
	$(PLANT_CC) -E $< -o $(@:.o=.i) && $(PLANT_CC) -c $< -o $@
$(BUILD)/planted/obj%/dynamics_f32.o $(BUILD)/planted/obj%/dynamics_f64.o $(BUILD)/planted/obj%/dynamics_host.o \
  $(BUILD)/planted/obj%/model.o $(BUILD)/planted/obj%/dyn_lod.o: $(PLANT_SRC) $(C_HEADERS) $(PLANT_BASE) | check-hdf5
	@mkdir -p $(BUILD)/planted/obj$*
	@for f in $(PLANT_SRC); do b=$(BUILD)/planted/base/$${f#c_ref/}; b=$${b%.c}; o=$(BUILD)/planted/obj$*/$$(basename $${f%.c}); \
	  $(PLANT_CC) -DHB_PLANT=$* -E $$f -o $$o.i || exit 1; \
	  if cmp -s $$o.i $$b.i; then cp $$b.o $$o.o; else echo "$(CC) … -DHB_PLANT=$* -c $$f"; \
	    $(PLANT_CC) -DHB_PLANT=$* -c $$f -o $$o.o || exit 1; fi; rm -f $$o.i; done
$(BUILD)/planted/hairsim-cpu-plant%: $(BUILD)/planted/obj%/dynamics_f32.o \
  $(filter-out $(PLANT_SRC:c_ref/%.c=$(OBJ)/%.o),$(SHARED_OBJ) $(CPU_OBJ))
	$(CC) -fopenmp $(BUILD)/planted/obj$*/*.o $(filter-out $(BUILD)/planted/%,$^) -o $@ $(HDF5_LIBS) -lm

ifeq ($(HAVE_NVCC),yes)
cuda: $(CUDA_BINS) $(BUILD)/sdf-sampling
# One object per source and math mode, so that make -j compiles them side by side; the two
# sources that hold the dynamic model's kernel tables once per precision (-DHB_DYN_REAL), which
# halves the longest compile. Only backend_cuda.cu takes the build's flags string.
CUDA_MODES := normal strict fastmath
CUDA_SPLIT := dynamic/kernels dynamic/lanes dynamic/lanes_grid dynamic/lanes_colliders dynamic/lanes_planes \
              dynamic/lanes_world_xpbd dynamic/lanes_world_ftl
CUDA_UNITS := $(filter-out $(CUDA_SPLIT) hostcheck/%,$(CUDA_SRC:cuda/%.cu=%)) $(foreach s,$(CUDA_SPLIT),$(s)-f32 $(s)-f64)
define CUDA_MODE_RULES
CUDA_OBJ_$(1) := $$(CUDA_UNITS:%=$$(OBJ)/cuda-$(1)/%.o)
$$(OBJ)/cuda-$(1)/%.o: cuda/%.cu $$(CUDA_HDR) $$(C_HEADERS) $$(DEVICE_OPT_STAMP)
	@mkdir -p $$(@D)
	$$(NVCC) $$(NVCC_BASE) -Icuda $$(NVCC_MODE_$(1))$$(NVCC_DEVICE_OPT) $$(HDF5_CFLAGS) -DHB_FLAGS='"$$(NVCC) $$(NVCC_BASE) $$(NVCC_MODE_$(1))$$(NVCC_DEVICE_OPT)"' \
	  -DHB_MATH_MODE='"$(1)"' -c $$< -o $$@
$$(OBJ)/cuda-$(1)/%-f32.o: cuda/%.cu $$(CUDA_HDR) $$(C_HEADERS) $$(DEVICE_OPT_STAMP)
	@mkdir -p $$(@D)
	$$(NVCC) $$(NVCC_BASE) -Icuda $$(NVCC_MODE_$(1))$$(NVCC_DEVICE_OPT) $$(HDF5_CFLAGS) -DHB_DYN_REAL=float -c $$< -o $$@
$$(OBJ)/cuda-$(1)/%-f64.o: cuda/%.cu $$(CUDA_HDR) $$(C_HEADERS) $$(DEVICE_OPT_STAMP)
	@mkdir -p $$(@D)
	$$(NVCC) $$(NVCC_BASE) -Icuda $$(NVCC_MODE_$(1))$$(NVCC_DEVICE_OPT) $$(HDF5_CFLAGS) -DHB_DYN_REAL=double -c $$< -o $$@
endef
$(foreach m,$(CUDA_MODES),$(eval $(call CUDA_MODE_RULES,$(m))))
$(BUILD)/hairsim-cuda: $(CUDA_OBJ_normal) $(SHARED_OBJ)
$(BUILD)/hairsim-cuda-strict: $(CUDA_OBJ_strict) $(SHARED_OBJ)
$(BUILD)/hairsim-cuda-fastmath: $(CUDA_OBJ_fastmath) $(SHARED_OBJ)
$(CUDA_BINS):
	@mkdir -p $(BUILD)
	$(NVCC) $(NVCC_ARCH) $^ -o $@ $(HDF5_LIBS) -ldl

# The host checks (tests/native): the CUDA port's model templates compiled for the host and
# run against the reference's objects; host code only, with the host compiler told the
# reference's rules (no FMA contraction, no fast math). The dynamic one at -O1: its many
# instantiations compile faster, and without contraction the level changes no IEEE result.
# dynamics_host.o plans the colliders' poses (docs/model.md §3.17): their objects link beside it
HOSTCHECK_WORLD_OBJ := $(OBJ)/dynamic/colliders.o $(OBJ)/dynamic/sdf_mesh.o $(OBJ)/runtime/cli.o $(OBJ)/runtime/input.o $(OBJ)/runtime/safe_write.o
HOSTCHECK_NVCC := $(NVCC) -std=c++17 -Ic_ref -Icuda -Xcompiler -ffp-contract=off,-fno-fast-math
hostcheck: $(HOSTCHECK_BINS)
$(BUILD)/hostcheck/paper_hostcheck_reference: HOSTCHECK_MODE := -O2 -DHB_REFERENCE_ARITHMETIC=1
$(BUILD)/hostcheck/paper_hostcheck_free: HOSTCHECK_MODE := -O2
$(BUILD)/hostcheck/paper_hostcheck_%: cuda/hostcheck/paper_hostcheck.cu cuda/paper/model.cuh cuda/tmath.cuh $(C_HEADERS) \
  $(OBJ)/paper/model.o $(OBJ)/runtime/params.o
	@mkdir -p $(@D)
	$(HOSTCHECK_NVCC) $(HOSTCHECK_MODE) $< $(OBJ)/paper/model.o $(OBJ)/runtime/params.o -o $@ -lm
$(BUILD)/hostcheck/dyn_hostcheck: cuda/hostcheck/dyn_hostcheck.cu cuda/hostcheck/hostcheck_scene.h cuda/dynamic/model.cuh cuda/tmath.cuh cuda/dynamic/kernels.cuh $(C_HEADERS) \
  $(OBJ)/dynamic/dynamics_f32.o $(OBJ)/dynamic/dynamics_f64.o $(OBJ)/dynamic/dynamics_host.o $(OBJ)/runtime/params.o \
  $(HOSTCHECK_WORLD_OBJ)
	@mkdir -p $(@D)
	$(HOSTCHECK_NVCC) -O1 $< $(filter %.o,$^) -o $@ -lm
$(BUILD)/hostcheck/post_hostcheck: cuda/hostcheck/post_hostcheck.cu cuda/hostcheck/hostcheck_rng.h cuda/hostcheck/hostcheck_scene.h cuda/dynamic/post.cuh cuda/dynamic/model.cuh cuda/tmath.cuh $(C_HEADERS) \
  $(OBJ)/dynamic/dyn_followers.o $(OBJ)/dynamic/dynamics_host.o $(OBJ)/runtime/params.o $(HOSTCHECK_WORLD_OBJ)
	@mkdir -p $(@D)
	$(HOSTCHECK_NVCC) -O1 $< $(filter %.o,$^) -o $@ -lm
$(BUILD)/hostcheck/lod_hostcheck: cuda/hostcheck/lod_hostcheck.cu cuda/hostcheck/hostcheck_rng.h cuda/dynamic/lod.cuh cuda/dynamic/model.cuh cuda/tmath.cuh $(C_HEADERS) \
  $(OBJ)/dynamic/dyn_lod.o
	@mkdir -p $(@D)
	$(HOSTCHECK_NVCC) -O1 $< $(filter %.o,$^) -o $@ -lm
# --draw's two paths on the host (OpenGL through EGL: loaded at run time, no GL library linked)
$(BUILD)/hostcheck/draw_hostcheck: cuda/hostcheck/draw_hostcheck.cu cuda/draw/view.cuh cuda/draw/egl_gl.cuh
	@mkdir -p $(@D)
	$(HOSTCHECK_NVCC) -O1 $< -o $@ -ldl -lm
# Issue #43's SDF sampling benchmark (tools/sdf_sampling.cu, docs/cuda.md): the reference builds
# the mesh's field; plain loads against a 3-D texture on the device. The normal build's flags.
SDF_TOOL_OBJ := $(HOSTCHECK_WORLD_OBJ) $(OBJ)/dynamic/dynamics_host.o $(OBJ)/runtime/params.o
$(BUILD)/sdf-sampling: tools/sdf_sampling.cu $(C_HEADERS) $(SDF_TOOL_OBJ) $(REV_STAMP)
	$(NVCC) $(NVCC_BASE) -DHB_GIT_REV='"$(GIT_REV)"' -DHB_FLAGS='"$(NVCC) $(NVCC_BASE)"' $< $(SDF_TOOL_OBJ) -o $@ -lm
else
hostcheck:
	@echo "error: nvcc not found: the host checks (cuda/hostcheck/) need it"; exit 1
cuda:
	@if [ -n "$(REQUIRE_NVCC)" ]; then echo "error: nvcc not found: the CUDA sources must compile here (install the CUDA toolkit or put nvcc on PATH)"; exit 1; fi
	@echo "note: nvcc not found: CUDA binaries not built (install the CUDA toolkit to build them)"
endif

# setup runs first, then the build (a recursive make, so that -j cannot build before it),
# on every core: the CUDA binaries and the C reference's feature instantiations take minutes
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
# The build on every core. In a log (not a terminal) a line at least every 25 s while it runs:
# make prints a line per command started, and one nvcc command can take longer than that.
define BUILD_LOGGED
if [ -t 1 ]; then $(MAKE) --no-print-directory -j$(JOBS) $(1); else \
	  ( s=0; while sleep 1; do s=$$((s + 1)); if [ $$((s % 25)) -eq 0 ]; then echo "build: $$s s elapsed"; fi; done ) & beat=$$!; \
	  $(MAKE) --no-print-directory -j$(JOBS) $(1); rc=$$?; kill $$beat 2>/dev/null; wait $$beat 2>/dev/null; exit $$rc; fi
endef
# The suite on TEST_JOBS workers (pytest-xdist, requirements-dev.txt; worksteal: an idle worker
# takes queued tests) where xdist is installed and TEST_JOBS > 1; else in one process, said.
TEST_JOBS ?= $(JOBS)
test: setup
	@$(call BUILD_LOGGED,all planted $(if $(HAVE_NVCC),hostcheck))
	@if [ "$(TEST_JOBS)" -gt 1 ] 2>/dev/null && $(RUN_PY) -c "import xdist" 2>/dev/null; then \
	  workers="-n $(TEST_JOBS) --dist worksteal"; \
	elif [ "$(TEST_JOBS)" -gt 1 ] 2>/dev/null; then \
	  echo "note: pytest-xdist is not installed: the suite runs in one process (make lint installs it)"; \
	fi; \
	echo "pytest tests -q -ra $$workers"; $(RUN_PY) -m pytest tests -q -ra $$workers

# make bench's run folder (untracked): results, then the report in $(OUT)/report. SCENE=my.toml:
# the dynamic studies on that scene or groom (docs/user_scene.md), into results/scene-<name>
# unless OUT is given
OUT ?= results/local
bench: setup
	@$(call BUILD_LOGGED,all)
	$(RUN_PY) -m harness bench$(if $(SCENE), --scene $(SCENE))$(if $(and $(SCENE),$(filter file,$(origin OUT))),, --out $(OUT))$(if $(BUDGET), --budget=$(BUDGET))$(if $(SHARD), --shard=$(SHARD))

# REPORT_FROM: the run folder to render (default results/local, make bench's), or one sweep's
# folder (its runs.csv: the paper report alone); REPORT_TO: where
# (default REPORT_FROM/report). The committed H200 report: make report REPORT_FROM=results/reference-h200 REPORT_TO=report
REPORT_FROM ?= $(OUT)
REPORT_TO ?= $(REPORT_FROM)/report
report: setup
	@[ -d "$(REPORT_FROM)" ] || { echo "error: $(REPORT_FROM) is not a run folder (run make bench, or give REPORT_FROM=results/reference-h200)"; exit 2; }
	@if [ -f "$(REPORT_FROM)/runs.csv" ]; then $(RUN_PY) -m harness report "$(REPORT_FROM)" --report-dir "$(REPORT_TO)"; fi
	@if [ -f "$(REPORT_FROM)/sweep/runs.csv" ]; then $(RUN_PY) -m harness report "$(REPORT_FROM)/sweep" --report-dir "$(REPORT_TO)"; fi
	@if [ -d "$(REPORT_FROM)/dynamic" ]; then $(RUN_PY) -m harness report-dynamic "$(REPORT_FROM)" --report-dir "$(REPORT_TO)"; fi
	@[ -f "$(REPORT_FROM)/runs.csv" ] || [ -f "$(REPORT_FROM)/sweep/runs.csv" ] || [ -d "$(REPORT_FROM)/dynamic" ] || { echo "error: $(REPORT_FROM) has neither runs.csv, sweep/runs.csv nor dynamic/: nothing to render"; exit 2; }

report-dynamic: setup
	$(RUN_PY) -m harness report-dynamic $(REPORT_FROM) --report-dir $(REPORT_TO)

# docs/harness.md's command and module reference, from the parser and the docstrings
docs: setup
	$(RUN_PY) -m harness docs

# ASan + UBSan over the C reference: a separate build in build/asan, the C tests run on it.
sanitize: setup check-hdf5
	$(MAKE) BUILD=build/asan COPT="-O1 -g -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all" \
	  CC="$(CC) -fsanitize=address,undefined" build/asan/hairsim-cpu
	HAIRBENCH_CPU_BIN=build/asan/hairsim-cpu ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions=$(CURDIR)/tests/support/lsan-hdf5.supp:print_suppressions=0 $(RUN_PY) -m pytest tests -q -m "not gpu" -k "cpu or rng or bad_input or resume or fault_probe or fault_matrix or binary_inputs"
	@for f in tests/fuzz/corpus/hair/*; do ASAN_OPTIONS=detect_leaks=1 build/asan/hairsim-cpu --groom $$f --stages init,simulate \
	  --quiet >/dev/null 2>&1; rc=$$?; if [ $$rc -ne 0 ] && [ $$rc -ne 2 ] && [ $$rc -ne 3 ]; then \
	  echo "error: build/asan/hairsim-cpu --groom $$f exited $$rc"; exit 1; fi; done; echo "sanitize: the HAIR seed corpus ran clean"

# libFuzzer over the HAIR groom reader (tests/fuzz/hair_fuzz.c) under ASan and UBSan, for FUZZ_SECONDS,
# from the committed seed corpus (tests/fuzz/corpus/hair/); the inputs it finds go to build/fuzz/corpus,
# a crash to build/fuzz/crash-*. Needs clang with libFuzzer (CI installs it: .ci/run).
FUZZ_CC ?= clang
FUZZ_SECONDS ?= 30
FUZZ_SRC := tests/fuzz/hair_fuzz.c c_ref/runtime/groom.c c_ref/runtime/params.c c_ref/runtime/input.c \
            c_ref/runtime/safe_write.c c_ref/runtime/cli.c
fuzz:
	@command -v $(FUZZ_CC) >/dev/null 2>&1 || { echo "error: $(FUZZ_CC) not found: make fuzz needs clang with libFuzzer (apt-get install clang)"; exit 1; }
	@mkdir -p $(BUILD)/fuzz/corpus
	$(FUZZ_CC) -std=c11 -D_DEFAULT_SOURCE -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
	  -Ic_ref $(FUZZ_SRC) -o $(BUILD)/fuzz/hair_fuzz -lm
	set -o pipefail; cd $(BUILD)/fuzz && ./hair_fuzz -max_total_time=$(FUZZ_SECONDS) -max_len=4096 -rss_limit_mb=2048 -print_final_stats=1 \
	  corpus $(CURDIR)/tests/fuzz/corpus/hair 2>&1 | tail -15

# compute-sanitizer (memcheck, racecheck) over every CUDA variant on a small run that also
# exercises the output, resume and end-to-end paths, and simulate on the strand and warp
# variants (both solvers and precisions, a resume from a middle frame). Needs a GPU.
SAN_RUN := --strands 1000 --points 16 --hair-length 10 --repeat 2 --end-to-end --quiet
# simulate (every variant that runs it, from --list-variants): every feature, P = 45 (the warp's lanes
# take one or two points) or the variant's most points, 3 frames, the frame loop
SAN_SIM := --strands 300 --points 45 --hair-length 10 --stages init,simulate --frames 3 --velocities all --repeat 2 \
  --substeps 2 --iterations 2 --bend-compliance 1e-6 --shape-compliance 1e-5 --wind-speed 300 --drag 2 \
  --gust-amplitude 0.5 --head-motion nod --quiet
# the world (docs/model.md §3.16, §3.17: lanes alone runs it): the grid at each rebuild and the default
# body with friction and bounded depenetration (also in 4 sweeps), both solvers and precisions; 40 substeps make a frame
# take several launches where the staged colliders do not fit one (docs/cuda.md)
SAN_WORLD := --strands 300 --points 32 --stages init,simulate --frames 2 --velocities all --variant lanes \
  --wind-speed 150 --gust-amplitude 0.5 --head-motion nod --quiet
SAN_BODY := --colliders configs/bodies/default.colliders --friction 0.3,0.2 --depenetration-speed 200
# the body's collision step in sweeps (docs/model.md §3.17): the warp's vote and the repeated sweep
SAN_SWEEPS := --collider-sweeps 4
# the colliders as contact planes (docs/model.md §3.17): each warp's planes in shared memory, kept in
# global memory between a frame's launches (40 substeps, or the grid built every substep)
SAN_PLANES := --contact-planes 3
# the splat's hash table (cuda/dynamic/world.cu): a fine grid over a small box, so that every splat
# block's box exceeds its window and some shares find no slot
SAN_HASH := --grid 256 --grid-box=-13,-45,-13,13,13,13 --grid-friction 0.1,0.02 --grid-volume 2000
# the splat's blocks taking runs of their strands' points (cuda/dynamic/world.cu: 2,048 strands or more;
# 29 points, so that a run's length is no power of two), the grid built every substep
SAN_RUNS := --strands 3000 --points 29 --frames 1 --grid 32 --grid-friction 0.05,0.01 --grid-volume 2000 \
  --grid-rebuild substep
# the lanes kernel's one-wave layout (cuda/dynamic/lanes.cu): fp32, 32 points, every feature, alone and with
# the held grid, at 16 strands more than one wave of G = 2 takes on this GPU (the record's layout)
SAN_WAVE := --points 32 --stages init,simulate --frames 1 --variant lanes --precision fp32 --bend-compliance 1e-6 \
  --shape-compliance 1e-4 --wind-speed 150 --gust-amplitude 0.5 --head-motion nod --drag 0.5 --quiet
sanitize-gpu: cuda sanitize-gpu-world
	@command -v compute-sanitizer >/dev/null 2>&1 || { echo "error: compute-sanitizer not found (it ships with the CUDA toolkit)"; exit 1; }
	@set -e; for v in $$($(PYTHON) -c "from harness.core import variants; print(*variants.names('cuda'))"); do for p in fp32 fp64; do \
	  echo "memcheck $$v $$p"; \
	  compute-sanitizer --tool memcheck --leak-check full --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_RUN) \
	    --variant $$v --precision $$p --output $(BUILD)/san-$$v-$$p.h5 --force; \
	  compute-sanitizer --tool memcheck --error-exitcode 9 $(BUILD)/hairsim-cuda --input $(BUILD)/san-$$v-$$p.h5 \
	    --stages wind,collide --variant $$v --end-to-end --quiet --output $(BUILD)/san-$$v-$$p-r.h5 --force; \
	  done; \
	  echo "racecheck $$v"; \
	  compute-sanitizer --tool racecheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_RUN) --variant $$v; \
	done; \
	for vp in $$($(PYTHON) -c "from harness.core import variants; d = variants.declared('cuda'); print(*(f'{v}:{min(45, d.max_points.get(v) or 45)}' for v in d.running('simulate')))"); do \
	  v=$${vp%%:*}; np=$${vp##*:}; for p in fp32 fp64; do for s in xpbd ftl; do \
	  echo "memcheck simulate $$v $$p $$s ($$np points)"; \
	  compute-sanitizer --tool memcheck --leak-check full --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_SIM) --points $$np \
	    --variant $$v --precision $$p --solver $$s --frame-loop --output $(BUILD)/san-sim-$$v-$$p-$$s.h5 --force; \
	  compute-sanitizer --tool memcheck --error-exitcode 9 $(BUILD)/hairsim-cuda --input $(BUILD)/san-sim-$$v-$$p-$$s.h5 \
	    --input-frame 2 --stages simulate --frames 1 --variant $$v --quiet --output $(BUILD)/san-sim-$$v-$$p-$$s-r.h5 --force; \
	  done; done; \
	  echo "racecheck simulate $$v"; \
	  compute-sanitizer --tool racecheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_SIM) --points $$np --variant $$v --frames 1; \
	  compute-sanitizer --tool racecheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_SIM) --points $$np --variant $$v --frames 1 --solver ftl; \
	done; rm -f $(BUILD)/san-*.h5; echo "compute-sanitizer: memcheck and racecheck found no errors in any variant"

sanitize-gpu-world: cuda
	@command -v compute-sanitizer >/dev/null 2>&1 || { echo "error: compute-sanitizer not found (it ships with the CUDA toolkit)"; exit 1; }
	@set -e; for p in fp32 fp64; do for s in xpbd ftl; do for w in "--grid 16 --grid-friction 0.05,0.01 --grid-volume 2000 --grid-rebuild held" \
	  "--grid 16 --grid-friction 0.05,0.01 --grid-volume 2000 --grid-rebuild substep" "$(SAN_BODY)" "$(SAN_BODY) --grid 16 --grid-friction 0.05" \
	  "$(SAN_BODY) $(SAN_SWEEPS)" "$(SAN_HASH)" "$(SAN_BODY) $(SAN_PLANES) $(SAN_SWEEPS)" \
	  "$(SAN_BODY) $(SAN_PLANES) --grid 16 --grid-friction 0.05 --grid-rebuild substep"; do \
	  echo "memcheck world $$p $$s $$w"; \
	  compute-sanitizer --tool memcheck --leak-check full --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WORLD) $$w \
	    --precision $$p --solver $$s --substeps 4 --output $(BUILD)/san-world-$$p-$$s.h5 --force; \
	  done; done; \
	  echo "memcheck world $$p 40 substeps"; \
	  compute-sanitizer --tool memcheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WORLD) $(SAN_BODY) --precision $$p \
	    --substeps 40 --frames 1 --output $(BUILD)/san-world-$$p-40.h5 --force; \
	  compute-sanitizer --tool memcheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WORLD) $(SAN_BODY) $(SAN_PLANES) \
	    --precision $$p --substeps 40 --frames 1 --output $(BUILD)/san-world-$$p-40.h5 --force; \
	  echo "racecheck world $$p"; \
	  compute-sanitizer --tool racecheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WORLD) $(SAN_BODY) --grid 16 \
	    --grid-friction 0.05,0.01 --grid-volume 2000 --grid-rebuild held --precision $$p --substeps 40 --frames 1; \
	  echo "racecheck world $$p hash table"; \
	  compute-sanitizer --tool racecheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WORLD) $(SAN_HASH) --precision $$p; \
	  echo "memcheck, racecheck world $$p $(SAN_RUNS)"; \
	  compute-sanitizer --tool memcheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WORLD) $(SAN_RUNS) --precision $$p \
	    --output $(BUILD)/san-world-$$p-runs.h5 --force; \
	  compute-sanitizer --tool racecheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WORLD) $(SAN_RUNS) --precision $$p; \
	  echo "racecheck world $$p $(SAN_SWEEPS)"; \
	  compute-sanitizer --tool racecheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WORLD) $(SAN_BODY) $(SAN_SWEEPS) \
	    --precision $$p --substeps 40 --frames 1; \
	  echo "racecheck world $$p $(SAN_PLANES)"; \
	  compute-sanitizer --tool racecheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WORLD) $(SAN_BODY) $(SAN_PLANES) \
	    --precision $$p --substeps 40 --frames 1; \
	done; \
	n=$$($(BUILD)/hairsim-cuda $(SAN_WAVE) --strands 64 --json | \
	  $(PYTHON) -c "import json, sys; print(json.load(sys.stdin)['stages'][-1]['layout']['strands_a_wave'] + 16)"); \
	for w in "" "--grid 32 --grid-friction 0.05,0.01 --grid-volume 2000 --grid-rebuild held"; do \
	  echo "memcheck, racecheck the one-wave layout ($$n strands) $$w"; \
	  compute-sanitizer --tool memcheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WAVE) --strands $$n $$w; \
	  compute-sanitizer --tool racecheck --error-exitcode 9 $(BUILD)/hairsim-cuda $(SAN_WAVE) --strands $$n $$w; \
	done; rm -f $(BUILD)/san-world-*.h5; echo "compute-sanitizer: memcheck and racecheck found no errors in the world's kernels"

# ---- lint and format: settings in pyproject.toml (ruff, mypy) and .clang-format ----
PY_SRC     := harness tests
C_FMT_SRC  := $(wildcard c_ref/*.c c_ref/*/*.c c_ref/*/*.h cuda/*.cu cuda/*.cuh cuda/*/*.cu cuda/*/*.cuh tools/*.cu tests/cpu/c/*.c tests/fuzz/*.c)
CLANG_FORMAT ?= clang-format

lint: lint-py lint-c

lint-py: setup
	@$(RUN_PY) -c "import ruff, mypy, xdist" 2>/dev/null || $(RUN_PY) -m pip install -q --disable-pip-version-check -r requirements-dev.txt
	$(RUN_PY) -m ruff check $(PY_SRC)
	$(RUN_PY) -m ruff format --check $(PY_SRC)
	$(RUN_PY) -m mypy

lint-c:
	$(CLANG_FORMAT) --dry-run --Werror $(C_FMT_SRC)

fmt:
	$(PYTHON) -m ruff format $(PY_SRC)
	$(CLANG_FORMAT) -i $(C_FMT_SRC)

clean:
	rm -rf $(BUILD)
