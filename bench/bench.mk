# bench.mk - builds the benchmark driver; bench/run.sh runs
#   make -f bench/bench.mk B=build/bench SOLVERS="pendulum_k2s2 ..."
# after generating $(B)/gen/NAME.c/.h and $(B)/gen/registry.c for SOLVERS.
CC      ?= cc
B       ?= build/bench
CFLAGS  := -O2 -g -std=c99 -Wall -Wextra -pedantic
GSL     := $(shell pkg-config --cflags gsl)
LIBS    := $(shell pkg-config --libs gsl) -lsundials_ida -lsundials_sunlinsoldense -lsundials_sunmatrixdense \
           -lsundials_sunlinsolband -lsundials_sunmatrixband \
           -lsundials_nvecserial -lm

SRC     := main.c methods.c fixedstep.c problems.c linalg.c timing.c sweep.c count.c reference.c \
           hbvm.c hbvm_adaptive.c hbvm_generic.c rattle.c ida.c ida_run.c gslpeers.c stiff.c abrun.c
OBJ     := $(addprefix $(B)/obj/,$(SRC:.c=.o)) $(B)/obj/ref.o
GENOBJ  := $(foreach s,$(SOLVERS),$(B)/gen/$(s).o $(B)/gen/$(s)_bench.o) $(B)/gen/registry.o

$(B)/bench: $(OBJ) $(GENOBJ)
	$(CC) -o $@ $^ $(LIBS)

$(B)/obj/%.o: bench/%.c $(wildcard bench/*.h)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(GSL) -Ibench -Itests -c -o $@ $<

# tests/ref.c, compiled as it is: the references of the paper's problems
$(B)/obj/ref.o: tests/ref.c tests/ref.h
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(GSL) -Itests -c -o $@ $<

$(B)/gen/%_bench.o: bench/hbvm_gen.c bench/hbvm.h $(B)/gen/%.h
	$(CC) $(CFLAGS) -Ibench -I$(B)/gen -DSOLVER=$* '-DSOLVER_H="$*.h"' -c -o $@ $<

$(B)/gen/registry.o: $(B)/gen/registry.c bench/hbvm.h
	$(CC) $(CFLAGS) -Ibench -c -o $@ $<

$(B)/gen/%.o: $(B)/gen/%.c $(B)/gen/%.h
	$(CC) $(CFLAGS) -I$(B)/gen -c -o $@ $<
