# hbvmgen - one flat Makefile.
#   make            the generator gen/hbvmgen and runtime/libhbvmrt.a
#   make check      install missing packages, build, run every test suite (plain and sanitized)
#   make demo       generate, build and run the pendulum with HBVM(2,2)
#   make generated  regenerate the committed solvers in generated/
#   make tables     the paper's tables beside ours (docs/tables.md)
#   make install    hbvmgen, libhbvmrt.a, hbvmrt.h, hbvmgen.1, hbvmrt.pc under
#                   $(DESTDIR)$(PREFIX) (PREFIX=/usr/local); make uninstall
#   make SANITIZE=1 ...   everything with -fsanitize=address,undefined

CC      ?= cc
CFLAGS  ?= -O2 -g
WARN    := -std=c99 -Wall -Wextra -pedantic
ifdef SANITIZE
SAN     := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
B       := build-san
else
SAN     :=
B       := build
endif
GSL     := $(shell pkg-config --cflags gsl 2>/dev/null)
GSLLIB  := $(shell pkg-config --libs gsl 2>/dev/null)
CHECK   := $(shell pkg-config --cflags check 2>/dev/null)
CHECKLIB:= $(shell pkg-config --libs check 2>/dev/null)
ALLCFLAGS = $(WARN) $(CFLAGS) $(SAN) -MMD -MP

GEN_SRC  := util.c ast.c dag.c ad.c mass.c model.c method.c lu.c step.c step_const.c step_poly.c step_newton.c emit_kernel.c emit_choice.c emit_api.c emit_predict.c emit_estimate.c emit_iterate.c emit_newton.c emit_end.c emit_step.c emit_project.c emit_batch.c emit_batch_step.c emit_solver.c emit_main.c
GEN_OBJ  := $(addprefix $(B)/gen/,$(GEN_SRC:.c=.o) parser.o lexer.o)
RT_OBJ   := $(patsubst runtime/%.c,$(B)/runtime/%.o,$(wildcard runtime/*.c))
SOLVERS  := $(shell grep -v '^\#' generated/LIST | awk 'NF {sub(/:.*/, "", $$1); print $$1 "_k" $$2 "s" $$3}')
SOLV_OBJ := $(addprefix $(B)/generated/,$(addsuffix .o,$(SOLVERS)))
# test-only models (tests/models/LIST), generated at build time
TSOLVERS := $(shell grep -v '^\#' tests/models/LIST | awk 'NF {sub(/:.*/, "", $$1); print $$1 "_k" $$2 "s" $$3}')
TSOLV_OBJ:= $(addprefix $(B)/tgen/,$(addsuffix .o,$(TSOLVERS)))
TEST_SRC := $(wildcard tests/check_*.c) tests/ref.c tests/paper.c tests/solvers.c tests/generate.c
TEST_OBJ := $(patsubst tests/%.c,$(B)/tests/%.o,$(TEST_SRC))


# Each flavour (build/, build-san/) links its own generator and runtime; `all`
# copies them to gen/hbvmgen and runtime/libhbvmrt.a, where users, scripts and
# tests find them, whenever they differ (so switching SANITIZE never leaves a
# stale or mismatched binary behind).
HBVMGEN  := $(B)/hbvmgen
LIBRT    := $(B)/libhbvmrt.a
LIBRT_OMP:= $(B)/libhbvmrt_omp.a
LIBRT_MPI:= $(B)/libhbvmrt_mpi.a
MPICC    ?= mpicc

.PHONY: all deps check demo generated tables figures bench fuzz clean install uninstall
all: $(HBVMGEN) $(LIBRT) $(LIBRT_OMP) $(if $(MPI),$(LIBRT_MPI))
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
	$(CC) $(WARN) -Werror $(CFLAGS) $(SAN) -Igenerated -c -o $@ $<

$(B)/tgen/stamp: tests/models/LIST $(wildcard tests/models/*.ham) $(wildcard models/*.ham) $(HBVMGEN)
	@mkdir -p $(@D)
	scripts/regen.sh $(HBVMGEN) $(B)/tgen tests/models/LIST tests/models
	@touch $@

$(B)/tgen/%.o: $(B)/tgen/stamp
	$(CC) $(WARN) -Werror $(CFLAGS) $(SAN) -I$(B)/tgen -c -o $@ $(B)/tgen/$*.c

$(B)/tests/%.o: tests/%.c $(B)/tgen/stamp
	@mkdir -p $(@D)
	$(CC) $(ALLCFLAGS) $(GSL) $(CHECK) -Igen -I$(B)/gen -Iruntime -Igenerated -I$(B)/tgen -Itests -c -o $@ $<

$(B)/tests/runner: $(TEST_OBJ) $(GEN_OBJ) $(SOLV_OBJ) $(TSOLV_OBJ) $(LIBRT)
	$(CC) $(SAN) -o $@ $^ $(CHECKLIB) $(GSLLIB) -lm

# make check runs every suite twice: as built, then built with ASan and UBSan
# (make SANITIZE=1 check runs only the latter); the plain binaries are put
# back in place at the end.
check: deps
	@scripts/deps.sh embedded clang mpi
	@$(MAKE) --no-print-directory $(B)/tests/runner all
	cd tests && HBVM_SANITIZED=$(if $(SANITIZE),1,) ../$(B)/tests/runner
ifndef SANITIZE
	@echo "== the same suites under -fsanitize=address,undefined"
	@$(MAKE) --no-print-directory SANITIZE=1 check
	@$(MAKE) --no-print-directory all
endif

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

# Installation. The pkg-config file is made from runtime/hbvmrt.pc.in with
# the prefix and directories of this install, so a program finds the
# runtime with `pkg-config --cflags --libs hbvmrt` alone.
PREFIX     ?= /usr/local
BINDIR     ?= $(PREFIX)/bin
LIBDIR     ?= $(PREFIX)/lib
INCLUDEDIR ?= $(PREFIX)/include
MANDIR     ?= $(PREFIX)/share/man
PCDIR      ?= $(LIBDIR)/pkgconfig
VERSION    := $(shell sed -n 's/^\#define HBVMGEN_VERSION "\(.*\)"/\1/p' gen/hbvmgen.h)

$(B)/hbvmrt.pc: runtime/hbvmrt.pc.in gen/hbvmgen.h FORCE
	@mkdir -p $(@D)
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@LIBDIR@|$(LIBDIR)|g' -e 's|@INCLUDEDIR@|$(INCLUDEDIR)|g' \
	    -e 's|@VERSION@|$(VERSION)|g' runtime/hbvmrt.pc.in > $@

install: all $(B)/hbvmrt.pc
	install -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(LIBDIR) $(DESTDIR)$(INCLUDEDIR) $(DESTDIR)$(MANDIR)/man1 $(DESTDIR)$(PCDIR)
	install -m 755 gen/hbvmgen $(DESTDIR)$(BINDIR)/hbvmgen
	install -m 644 runtime/libhbvmrt.a $(DESTDIR)$(LIBDIR)/libhbvmrt.a
	install -m 644 runtime/hbvmrt.h $(DESTDIR)$(INCLUDEDIR)/hbvmrt.h
	install -m 644 docs/hbvmgen.1 $(DESTDIR)$(MANDIR)/man1/hbvmgen.1
	install -m 644 $(B)/hbvmrt.pc $(DESTDIR)$(PCDIR)/hbvmrt.pc

uninstall:
	rm -f $(DESTDIR)$(BINDIR)/hbvmgen $(DESTDIR)$(LIBDIR)/libhbvmrt.a $(DESTDIR)$(INCLUDEDIR)/hbvmrt.h \
	      $(DESTDIR)$(MANDIR)/man1/hbvmgen.1 $(DESTDIR)$(PCDIR)/hbvmrt.pc

FORCE:

fuzz:
	@scripts/deps.sh fuzz
	tests/fuzz/run.sh $(FUZZ_SECONDS)
	tests/fuzz/run_runtime.sh $(FUZZ_SECONDS)

clean:
	rm -rf build build-san gen/hbvmgen runtime/libhbvmrt.a runtime/libhbvmrt_omp.a runtime/libhbvmrt_mpi.a demo

-include $(shell find $(B) -name '*.d' 2>/dev/null)
