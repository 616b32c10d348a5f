# hbvmgen - one flat Makefile.
#   make            the generator gen/hbvmgen and runtime/libhbvmrt.a
#   make check      install missing packages, build, run the test suites (plain and
#                   sanitized; see "make check, make check-long" below)
#   make check-long the long test cases, and every case under the sanitizers
#   make demo       generate, build and run the pendulum with HBVM(2,2)
#   make generated  regenerate the committed solvers in generated/
#   make tables     the paper's tables beside ours (docs/tables.md)
#   make bench-stiff  the stiff benchmark alone (bench/stiff/run.sh; make bench runs it too)
#   make install    hbvmgen, the runtimes (libhbvmrt.a, .so, _omp.a, _mpi.a with MPI=1),
#                   hbvmrt.h, hbvmgen.1, the .pc files, the docs under
#                   $(DESTDIR)$(PREFIX) (PREFIX=/usr/local); make uninstall
#   make SANITIZE=1 ...   everything with -fsanitize=address,undefined

CC      ?= cc
CFLAGS  ?= -O2 -g
WARN    := -std=c99 -Wall -Wextra -pedantic
ifdef SANITIZE
SAN     := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
B       := build-san
# the generated solvers with line tables only: gcc's variable tracking (-g) on a
# sanitized 1 MB step (butane_polynewton) took 15 GB and 234 s, two such at once
# near the machine's 24 GB; -g1 takes 0.4 GB and 16 s, and ASan's reports keep
# their file:line
SOLVER_G:= -g1
else
SAN     :=
B       := build
SOLVER_G:=
endif
GSL     := $(shell pkg-config --cflags gsl 2>/dev/null)
GSLLIB  := $(shell pkg-config --libs gsl 2>/dev/null)
CHECK   := $(shell pkg-config --cflags check 2>/dev/null)
CHECKLIB:= $(shell pkg-config --libs check 2>/dev/null)
ALLCFLAGS = $(WARN) $(CFLAGS) $(SAN) -MMD -MP

GEN_SRC  := util.c ast.c dag.c bounds.c ad.c mass.c model.c stiffness.c switch.c method.c lu.c step.c step_const.c step_poly.c step_newton.c mass_q.c step_mq.c emit_kernel.c emit_choice.c emit_api.c emit_predict.c emit_estimate.c emit_iterate.c emit_newton.c emit_mq.c emit_end.c emit_step.c emit_project.c emit_batch.c emit_batch_step.c emit_batch_mq.c emit_batch_by_lane.c emit_solver.c emit_main.c roll.c roll_pair.c roll_newton.c emit_rolled.c emit_rolled_poly.c emit_rolled_pairs.c emit_rolled_batch.c emit_rolled_newton.c emit_rolled_tcon.c
GEN_OBJ  := $(addprefix $(B)/gen/,$(GEN_SRC:.c=.o) parser.o lexer.o)
RT_OBJ   := $(patsubst runtime/%.c,$(B)/runtime/%.o,$(wildcard runtime/*.c))
SOLVERS  := $(shell grep -v '^\#' generated/LIST | awk 'NF {sub(/:.*/, "", $$1); print $$1 "_k" $$2 "s" $$3}')
SOLV_OBJ := $(addprefix $(B)/generated/,$(addsuffix .o,$(SOLVERS)))
# test-only models (tests/models/LIST), generated at build time
TSOLVERS := $(shell grep -v '^\#' tests/models/LIST | awk 'NF {sub(/:.*/, "", $$1); print $$1 "_k" $$2 "s" $$3}')
TSOLV_OBJ:= $(addprefix $(B)/tgen/,$(addsuffix .o,$(TSOLVERS)))
TEST_SRC := $(wildcard tests/check_*.c) tests/ref.c tests/paper.c tests/solvers.c tests/generate.c tests/mq_common.c
TEST_OBJ := $(patsubst tests/%.c,$(B)/tests/%.o,$(TEST_SRC))


# Each flavour (build/, build-san/) links its own generator and runtime; `all`
# copies them to gen/hbvmgen and runtime/libhbvmrt.a, where users, scripts and
# tests find them, whenever they differ (so switching SANITIZE never leaves a
# stale or mismatched binary behind).
HBVMGEN  := $(B)/hbvmgen
LIBRT    := $(B)/libhbvmrt.a
LIBRT_OMP:= $(B)/libhbvmrt_omp.a
LIBRT_MPI:= $(B)/libhbvmrt_mpi.a
LIBRT_SO := $(B)/libhbvmrt.so
MPICC    ?= mpicc

.PHONY: all deps check check-long check-build check-san-build check-san-all-build demo generated tables figures bench bench-stiff fuzz clean install uninstall
BINS     := $(HBVMGEN) $(LIBRT) $(LIBRT_OMP) $(LIBRT_SO) $(if $(MPI),$(LIBRT_MPI))
all: $(BINS)
	@cmp -s $(HBVMGEN) gen/hbvmgen || cp $(HBVMGEN) gen/hbvmgen
	@cmp -s $(LIBRT) runtime/libhbvmrt.a || cp $(LIBRT) runtime/libhbvmrt.a
	@cmp -s $(LIBRT_OMP) runtime/libhbvmrt_omp.a || cp $(LIBRT_OMP) runtime/libhbvmrt_omp.a
	@$(if $(MPI),cmp -s $(LIBRT_MPI) runtime/libhbvmrt_mpi.a || cp $(LIBRT_MPI) runtime/libhbvmrt_mpi.a)

gen/hbvmgen runtime/libhbvmrt.a: all

deps:
	@scripts/deps.sh

$(B)/gen/parser.c $(B)/gen/parser.h &: gen/parser.y
	@mkdir -p $(@D)
	bison -Wall -Werror --defines=$(B)/gen/parser.h -o $(B)/gen/parser.c $<

$(B)/gen/lexer.c $(B)/gen/lexer.h &: gen/lexer.l $(B)/gen/parser.h
	@mkdir -p $(@D)
	flex --header-file=$(B)/gen/lexer.h -o $(B)/gen/lexer.c $<

# flex's output is not pedantic-clean; it gets the same warnings minus that one.
$(B)/gen/lexer.o: $(B)/gen/lexer.c
	$(CC) $(WARN) -Wno-unused-function $(CFLAGS) $(SAN) -MMD -MP -Igen -I$(B)/gen -c -o $@ $<

$(B)/gen/parser.o: $(B)/gen/parser.c $(B)/gen/lexer.h
	$(CC) $(ALLCFLAGS) -Igen -I$(B)/gen -c -o $@ $<

$(B)/gen/%.o: gen/%.c | $(B)/gen/parser.h
	@mkdir -p $(@D)
	$(CC) $(ALLCFLAGS) $(GSL) -Igen -I$(B)/gen -c -o $@ $<

$(HBVMGEN): $(GEN_OBJ) $(B)/gen/main.o
	$(CC) $(SAN) -o $@ $^ $(GSLLIB) -lm

$(B)/runtime/%.o: runtime/%.c
	@mkdir -p $(@D)
	$(CC) $(ALLCFLAGS) -Iruntime -c -o $@ $<

$(LIBRT): $(RT_OBJ)
	rm -f $@
	ar rcs $@ $^

# The runtime again for ensembles (runtime/ensemble.c) on threads:
# libhbvmrt_omp.a, linked with -fopenmp; and with MPI=1 on MPI ranks too:
# libhbvmrt_mpi.a, linked with $(MPICC) -fopenmp (scripts/deps.sh mpi).
$(B)/runtime-omp/%.o: runtime/%.c
	@mkdir -p $(@D)
	$(CC) $(ALLCFLAGS) -fopenmp -Iruntime -c -o $@ $<

$(B)/runtime-mpi/%.o: runtime/%.c
	@mkdir -p $(@D)
	$(MPICC) $(ALLCFLAGS) -fopenmp -DHBVMRT_MPI -Iruntime -c -o $@ $<

$(LIBRT_OMP): $(patsubst runtime/%.c,$(B)/runtime-omp/%.o,$(wildcard runtime/*.c))
	rm -f $@
	ar rcs $@ $^

$(LIBRT_MPI): $(patsubst runtime/%.c,$(B)/runtime-mpi/%.o,$(wildcard runtime/*.c))
	rm -f $@
	ar rcs $@ $^

# The committed solvers compile with -Werror: they must stay warning-free.
$(B)/generated/%.o: generated/%.c generated/%.h
	@mkdir -p $(@D)
	$(CC) $(WARN) -Werror $(CFLAGS) $(SOLVER_G) $(SAN) -Igenerated -c -o $@ $<

$(B)/tgen/stamp: tests/models/LIST $(wildcard tests/models/*.ham) $(wildcard models/*.ham) $(HBVMGEN)
	@mkdir -p $(@D)
	scripts/regen.sh $(HBVMGEN) $(B)/tgen tests/models/LIST tests/models
	@touch $@

$(B)/tgen/%.o: $(B)/tgen/stamp
	$(CC) $(WARN) -Werror $(CFLAGS) $(SOLVER_G) $(SAN) -I$(B)/tgen -c -o $@ $(B)/tgen/$*.c

# make check's sanitized run (SAN_SOLVERS=plain) links the plain build's
# solvers (build/generated, build/tgen) into build-san/tests/runner-mix: the
# generator, runtime and tests are instrumented, and each solver is compiled
# once for both runs. The full sanitized runner, build-san/tests/runner (make
# check-long, make SANITIZE=1 check), instruments the solvers too.
ifeq ($(SANITIZE)$(SAN_SOLVERS),1plain)
SB       := build
RUNNER   := $(B)/tests/runner-mix
build/tgen/stamp:
	@echo "$@: missing; SAN_SOLVERS=plain links the plain build's solvers (make build/tests/runner first)" >&2; exit 1
build/generated/%.o build/tgen/%.o:
	@echo "$@: missing; SAN_SOLVERS=plain links the plain build's solvers (make build/tests/runner first)" >&2; exit 1
else
SB       := $(B)
RUNNER   := $(B)/tests/runner
endif

$(B)/tests/%.o: tests/%.c $(SB)/tgen/stamp
	@mkdir -p $(@D)
	$(CC) $(ALLCFLAGS) $(GSL) $(CHECK) -Igen -I$(B)/gen -Iruntime -Igenerated -I$(SB)/tgen -Itests -c -o $@ $<

$(RUNNER): $(TEST_OBJ) $(GEN_OBJ) $(patsubst $(B)/%,$(SB)/%,$(SOLV_OBJ) $(TSOLV_OBJ)) $(LIBRT)
	$(CC) $(SAN) -o $@ $^ $(CHECKLIB) $(GSLLIB) -lm

# ---- make check, make check-long ----
# One runner per suite of tests/suites.def, CHECK_JOBS of them at a time; the
# test cases tagged "long" (tcase_set_tags) run in check-long only, those
# tagged "sanlong" (the generated solvers' arithmetic, many solvers compiled,
# builds as a user does) are left out of check's sanitized run. What runs where:
#   make check       plain: every suite, no "long" case;
#                    sanitized (runner-mix): every suite, no "long" or "sanlong" case
#   make check-long  plain: the "long" cases;
#                    sanitized (runner, solvers instrumented too): every case
#   make SANITIZE=1 check   the latter alone
# Each suite's output is printed whole when it ends (build/check/RUN/SUITE.log,
# with Check's XML log of every test's time beside it; not at all when the
# run left out all its cases), then the run's total in Check's words; the
# target fails when any suite fails.
SUITES     := $(shell sed -n 's/^SUITE(\([A-Za-z0-9_]*\))$$/\1/p' tests/suites.def)
CHECK_JOBS ?= $(shell nproc 2>/dev/null || echo 2)
# -jCHECK_JOBS, unless this make already shares a job server (make -jN check)
CHECK_J     = $(if $(findstring jobserver,$(MAKEFLAGS)),,-j$(CHECK_JOBS))
CK         := build/check
# the suites that take longest start first, so that no job is left alone at the end
CHECK_FIRST:= ensemble init errors docs install runtime
CHECK_ORDER:= $(foreach s,$(CHECK_FIRST),$(filter $(s),$(SUITES))) $(filter-out $(CHECK_FIRST),$(SUITES))
SUBMAKE     = $(MAKE) --no-print-directory

# $(call suite_rule,RUN,RUNNER,ENVIRONMENT): the rule running one suite of run
# RUN: its output in $(CK)/RUN/SUITE.log, its exit status in SUITE.rc.
define suite_rule
$(CK)/$1/%.rc: FORCE
	@mkdir -p $$(@D) && rm -f $$(@D)/$$*.xml
	@cd tests && env $3 CK_XML_LOG_FILE_NAME=../$(CK)/$1/$$*.xml ../$2 $$* >../$(CK)/$1/$$*.log 2>&1; \
	  echo $$$$? >../$$@; grep -qx '100%: Checks: 0, Failures: 0, Errors: 0' ../$(CK)/$1/$$*.log || cat ../$(CK)/$1/$$*.log
check-run-$1: $(CHECK_ORDER:%=$(CK)/$1/%.rc)
	@scripts/check_total.sh $(CK)/$1 "$1" $(SUITES)
endef
$(eval $(call suite_rule,plain,build/tests/runner,CK_EXCLUDE_TAGS=long HBVM_SANITIZED=))
$(eval $(call suite_rule,sanitized,build-san/tests/runner-mix,CK_EXCLUDE_TAGS='long sanlong' HBVM_SANITIZED=1))
# check-long's runs share the cores with a sanitized build: Check's timeouts x4
$(eval $(call suite_rule,long,build/tests/runner,CK_INCLUDE_TAGS=long HBVM_SANITIZED= CK_TIMEOUT_MULTIPLIER=4))
$(eval $(call suite_rule,sanitized-all,build-san/tests/runner,HBVM_SANITIZED=1 CK_TIMEOUT_MULTIPLIER=4))

# Build a sanitized runner quietly (its log in $(CK)/), for a run beside another.
# $1: make's variables for it.
san_build = mkdir -p $(CK) && $(SUBMAKE) SANITIZE=1 $1 >$(CK)/san-build.log 2>&1 || { cat $(CK)/san-build.log; exit 1; }
check-build: $(RUNNER) $(BINS)
check-san-build:
	+@$(call san_build,SAN_SOLVERS=plain check-build)
check-san-all-build:
	+@$(call san_build,check-build)

# Run $1 with the sanitized generator and runtime in gen/ and runtime/, where
# the tests take them from; the plain ones are put back, whatever the result.
san_run = $(SUBMAKE) SANITIZE=1 all && { st=0; $(SUBMAKE) $(CHECK_J) check-run-$1 || st=$$?; $(SUBMAKE) all; exit $$st; }

check: deps
	@scripts/deps.sh embedded clang mpi
ifdef SANITIZE
	+@$(SUBMAKE) $(CHECK_J) $(RUNNER) all
	+@$(SUBMAKE) SANITIZE= $(CHECK_J) check-run-sanitized-all
else
	+@$(SUBMAKE) $(CHECK_J) build/tests/runner all
	+@$(SUBMAKE) $(CHECK_J) check-san-build check-run-plain
	+@$(call san_run,sanitized)
endif

check-long: deps
	@scripts/deps.sh embedded clang mpi
	+@$(SUBMAKE) $(CHECK_J) build/tests/runner all
	+@$(SUBMAKE) $(CHECK_J) check-san-all-build check-run-long
	+@$(call san_run,sanitized-all)

generated: all
	scripts/regen.sh gen/hbvmgen generated

demo: deps
	@$(MAKE) --no-print-directory all
	scripts/demo.sh

$(B)/tests/tables: $(B)/tests/tables.o $(B)/tests/paper.o $(B)/tests/ref.o $(B)/tests/solvers.o $(SOLV_OBJ)
	$(CC) $(SAN) -o $@ $^ $(GSLLIB) -lm

tables: deps
	@$(MAKE) --no-print-directory $(B)/tests/tables
	@mkdir -p docs
	$(B)/tests/tables tests/data docs/tables.md
	@echo "tables: written to docs/tables.md"


figures: deps
	@scripts/deps.sh bench
	@$(MAKE) --no-print-directory all
	scripts/figures.sh

bench: deps
	@scripts/deps.sh bench
	@$(MAKE) --no-print-directory all
	bench/run.sh

# the stiff benchmark alone (issue 27; also part of make bench)
bench-stiff: deps
	@scripts/deps.sh bench
	@$(MAKE) --no-print-directory all
	bench/stiff/run.sh

# Installation. The pkg-config files (hbvmrt, hbvmrt_omp, and with MPI=1
# hbvmrt_mpi) are made from runtime/hbvmrt.pc.in with the prefix and
# directories of this install, so a program finds a runtime with
# `pkg-config --cflags --libs hbvmrt` alone. Every path is quoted for the
# shell ($(call shq,...)): PREFIX and DESTDIR may hold spaces and quotes.
# The generator is installed stripped (STRIP= keeps its symbols).
PREFIX     ?= /usr/local
BINDIR     ?= $(PREFIX)/bin
LIBDIR     ?= $(PREFIX)/lib
INCLUDEDIR ?= $(PREFIX)/include
MANDIR     ?= $(PREFIX)/share/man
PCDIR      ?= $(LIBDIR)/pkgconfig
DOCDIR     ?= $(PREFIX)/share/doc/hbvmgen
STRIP      ?= strip
VERSION    := $(shell sed -n 's/^\#define HBVMGEN_VERSION "\(.*\)"/\1/p' gen/hbvmgen.h)
SOMAJOR    := $(firstword $(subst ., ,$(VERSION)))
PC_NAMES   := hbvmrt hbvmrt_omp $(if $(MPI),hbvmrt_mpi)
PC_WHAT_hbvmrt_omp   := , ensembles on OpenMP threads
PC_WHAT_hbvmrt_mpi   := , ensembles on MPI ranks (link with mpicc) and OpenMP threads
PC_OPENMP_hbvmrt_omp := -fopenmp
PC_OPENMP_hbvmrt_mpi := -fopenmp
DOC_FILES  := README.md $(wildcard docs/*.md docs/*.png)
# a make value as one shell word
shq         = '$(subst ','\'',$1)'
PC_ENV      = PC_PREFIX=$(call shq,$(PREFIX)) PC_LIBDIR=$(call shq,$(LIBDIR)) \
              PC_INCLUDEDIR=$(call shq,$(INCLUDEDIR)) PC_VERSION=$(call shq,$(VERSION))
# $(call inst,MODE,FILES,DIR): install FILES into $(DESTDIR)DIR
inst        = install -m $1 $2 $(call shq,$(DESTDIR)$3)

# The runtime as a shared library too: objects compiled with -fPIC, the file
# libhbvmrt.so.VERSION with the soname libhbvmrt.so.MAJOR.
$(B)/runtime-pic/%.o: runtime/%.c
	@mkdir -p $(@D)
	$(CC) $(ALLCFLAGS) -fPIC -Iruntime -c -o $@ $<

$(LIBRT_SO): $(patsubst runtime/%.c,$(B)/runtime-pic/%.o,$(wildcard runtime/*.c))
	$(CC) $(SAN) -shared -Wl,-soname,libhbvmrt.so.$(SOMAJOR) -o $@ $^ -lm

# The .pc files are written straight into place (a file in build/ would be
# shared by two installs running at once, as two test suites may).
install: all
	install -d $(call shq,$(DESTDIR)$(BINDIR)) $(call shq,$(DESTDIR)$(LIBDIR)) $(call shq,$(DESTDIR)$(INCLUDEDIR)) \
	  $(call shq,$(DESTDIR)$(MANDIR)/man1) $(call shq,$(DESTDIR)$(PCDIR)) \
	  $(call shq,$(DESTDIR)$(DOCDIR)/examples) $(call shq,$(DESTDIR)$(DOCDIR)/models)
	install -m 755 $(if $(STRIP),-s --strip-program=$(call shq,$(STRIP))) $(HBVMGEN) $(call shq,$(DESTDIR)$(BINDIR)/hbvmgen)
	$(call inst,644,$(LIBRT) $(LIBRT_OMP) $(if $(MPI),$(LIBRT_MPI)),$(LIBDIR))
	$(call inst,755,$(LIBRT_SO),$(LIBDIR)/libhbvmrt.so.$(VERSION))
	ln -sf libhbvmrt.so.$(VERSION) $(call shq,$(DESTDIR)$(LIBDIR)/libhbvmrt.so.$(SOMAJOR))
	ln -sf libhbvmrt.so.$(SOMAJOR) $(call shq,$(DESTDIR)$(LIBDIR)/libhbvmrt.so)
	$(call inst,644,runtime/hbvmrt.h,$(INCLUDEDIR))
	$(call inst,644,docs/hbvmgen.1,$(MANDIR)/man1)
	$(foreach n,$(PC_NAMES),$(PC_ENV) PC_NAME=$(n) PC_WHAT=$(call shq,$(PC_WHAT_$(n))) \
	  PC_OPENMP=$(call shq,$(PC_OPENMP_$(n))) scripts/pcfile.sh runtime/hbvmrt.pc.in >$(call shq,$(DESTDIR)$(PCDIR)/$(n).pc) &&) true
	$(call inst,644,$(DOC_FILES),$(DOCDIR))
	$(call inst,644,$(wildcard docs/examples/*),$(DOCDIR)/examples)
	$(call inst,644,$(wildcard models/*.ham),$(DOCDIR)/models)

uninstall:
	rm -f $(call shq,$(DESTDIR)$(BINDIR)/hbvmgen) $(call shq,$(DESTDIR)$(INCLUDEDIR)/hbvmrt.h) \
	  $(call shq,$(DESTDIR)$(MANDIR)/man1/hbvmgen.1) \
	  $(foreach f,libhbvmrt.a libhbvmrt_omp.a libhbvmrt_mpi.a libhbvmrt.so libhbvmrt.so.$(SOMAJOR) \
	    libhbvmrt.so.$(VERSION),$(call shq,$(DESTDIR)$(LIBDIR)/$(f))) \
	  $(foreach f,hbvmrt hbvmrt_omp hbvmrt_mpi,$(call shq,$(DESTDIR)$(PCDIR)/$(f).pc))
	rm -f $(foreach f,$(notdir $(DOC_FILES)) $(addprefix examples/,$(notdir $(wildcard docs/examples/*))) \
	  $(addprefix models/,$(notdir $(wildcard models/*.ham))),$(call shq,$(DESTDIR)$(DOCDIR)/$(f)))
	-rmdir $(call shq,$(DESTDIR)$(DOCDIR)/examples) $(call shq,$(DESTDIR)$(DOCDIR)/models) $(call shq,$(DESTDIR)$(DOCDIR)) 2>/dev/null || true

FORCE:

fuzz:
	@scripts/deps.sh fuzz
	tests/fuzz/run.sh $(FUZZ_SECONDS)
	tests/fuzz/run_runtime.sh $(FUZZ_SECONDS)

clean:
	rm -rf build build-san gen/hbvmgen runtime/libhbvmrt.a runtime/libhbvmrt_omp.a runtime/libhbvmrt_mpi.a demo

-include $(shell find $(B) -name '*.d' 2>/dev/null)
