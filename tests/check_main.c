/* check_main.c - the one test runner: every suite of tests/suites.def, run
 * from tests/.
 *
 *   runner            every suite, one after the other
 *   runner NAME...    only the suites named (the Makefile's per-suite runs)
 *
 * Check's own variables still apply: CK_RUN_SUITE, CK_RUN_CASE, and
 * CK_EXCLUDE_TAGS / CK_INCLUDE_TAGS, which make check and make check-long
 * use to split the test cases tagged "long" and "numeric" (see the README,
 * "Testing"). Exit status 0 when every check passed, 1 otherwise, 2 for an
 * unknown suite name. */
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SUITE(name) Suite *name##_suite(void);
#include "suites.def"
#undef SUITE

static const struct {
  const char *name;
  Suite *(*make)(void);
} suites[] = {
#define SUITE(name) {#name, name##_suite},
#include "suites.def"
#undef SUITE
};

#define NSUITES (sizeof suites / sizeof suites[0])

/* Whether suite i is among the names given (all of them when none is). */
static int wanted(size_t i, int argc, char **argv) {
  if (argc < 2) return 1;
  for (int a = 1; a < argc; a++)
    if (strcmp(argv[a], suites[i].name) == 0) return 1;
  return 0;
}

int main(int argc, char **argv) {
  for (int a = 1; a < argc; a++) {
    size_t i = 0;
    while (i < NSUITES && strcmp(argv[a], suites[i].name) != 0) i++;
    if (i == NSUITES) {
      fprintf(stderr, "runner: no suite '%s' in tests/suites.def\n", argv[a]);
      return 2;
    }
  }
  SRunner *sr = NULL;
  for (size_t i = 0; i < NSUITES; i++) {
    if (!wanted(i, argc, argv)) continue;
    if (sr)
      srunner_add_suite(sr, suites[i].make());
    else
      sr = srunner_create(suites[i].make());
  }
  srunner_run_all(sr, CK_NORMAL);
  int failed = srunner_ntests_failed(sr);
  srunner_free(sr);
  return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
