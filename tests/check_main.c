/* check_main.c - the one test runner: every module's suite, run from tests/. */
#include <check.h>
#include <stdlib.h>

Suite *parser_suite(void);
Suite *errors_suite(void);
Suite *dag_suite(void);
Suite *ad_suite(void);
Suite *ref_suite(void);
Suite *runtime_suite(void);
Suite *solver_suite(void);
Suite *tables_suite(void);
Suite *lean_suite(void);
Suite *stress_suite(void);
Suite *docs_suite(void);
Suite *files_suite(void);
Suite *poly_suite(void);
Suite *init_suite(void);
Suite *mass_suite(void);
Suite *batch_suite(void);
Suite *ensemble_suite(void);
Suite *rolled_suite(void);
Suite *errest_suite(void);
Suite *adaptive_suite(void);
Suite *dense_suite(void);
Suite *events_suite(void);
Suite *newton_suite(void);

int main(void) {
  SRunner *sr = srunner_create(parser_suite());
  srunner_add_suite(sr, errors_suite());
  srunner_add_suite(sr, dag_suite());
  srunner_add_suite(sr, ad_suite());
  srunner_add_suite(sr, ref_suite());
  srunner_add_suite(sr, runtime_suite());
  srunner_add_suite(sr, solver_suite());
  srunner_add_suite(sr, tables_suite());
  srunner_add_suite(sr, lean_suite());
  srunner_add_suite(sr, stress_suite());
  srunner_add_suite(sr, docs_suite());
  srunner_add_suite(sr, files_suite());
  srunner_add_suite(sr, poly_suite());
  srunner_add_suite(sr, init_suite());
  srunner_add_suite(sr, mass_suite());
  srunner_add_suite(sr, batch_suite());
  srunner_add_suite(sr, ensemble_suite());
  srunner_add_suite(sr, rolled_suite());
  srunner_add_suite(sr, errest_suite());
  srunner_add_suite(sr, adaptive_suite());
  srunner_add_suite(sr, dense_suite());
  srunner_add_suite(sr, events_suite());
  srunner_add_suite(sr, newton_suite());
  srunner_run_all(sr, CK_NORMAL);
  int failed = srunner_ntests_failed(sr);
  srunner_free(sr);
  return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
