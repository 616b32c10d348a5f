/* check_install.c - `make install` as packagers and users run it: each test
 * runs a scenario of tests/install.sh (see there) in a temporary directory,
 * from tests/:
 *   destdir  a DESTDIR install: every file, the shared runtime's soname, and
 *            drivers linked through pkg-config against libhbvmrt.so,
 *            libhbvmrt.a, hbvmrt_omp (and hbvmrt_mpi with mpicc);
 *   strip    the installed generator is stripped; the README names the
 *            shared libraries it needs at run time;
 *   quoted   a PREFIX with a space and quotes installs there and nowhere
 *            else, its pkg-config flags build a driver, uninstall cleans up.
 * The suite is install_suite() (tests/suites.def); its sanitized run is in
 * make check-long (tag "sanlong"). */
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>

Suite *install_suite(void);

static const char *const scenarios[] = {"destdir", "strip", "quoted"};

START_TEST(install_scenario)
{
  char cmd[128];
  snprintf(cmd, sizeof cmd, "sh install.sh %s", scenarios[_i]);
  int rc = system(cmd);
  ck_assert_msg(rc != -1 && WIFEXITED(rc) && WEXITSTATUS(rc) == 0, "%s failed (its message is above)", cmd);
}
END_TEST

Suite *install_suite(void)
{
  Suite *s = suite_create("install");
  TCase *tc = tcase_create("install");
  tcase_set_tags(tc, "sanlong");
  tcase_set_timeout(tc, 300);
  tcase_add_loop_test(tc, install_scenario, 0, (int)(sizeof scenarios / sizeof scenarios[0]));
  suite_add_tcase(s, tc);
  return s;
}
