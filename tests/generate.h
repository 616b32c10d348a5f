/* generate.h - run the generator on a model text from a test. */
#ifndef HBVM_TESTS_GENERATE_H
#define HBVM_TESTS_GENERATE_H

#include <stddef.h>

/* Generate `text` as a model (../gen/hbvmgen flags, from tests/) in a fresh
 * directory, removed afterwards; returns the generated C source (malloc'd,
 * up to 4 MiB) or NULL when the generator fails. */
char *generate_source(const char *text, const char *flags);

/* The contents of a file (malloc'd, NUL-terminated), or NULL. */
char *read_text(const char *path);

/* The number of temporaries ("const double t") in the kernel whose
 * definition starts at the first occurrence of `head` ("_sweep(") in src. */
int kernel_temporaries(const char *src, const char *head);

/* The generator's output (stdout and stderr, up to size - 1 bytes, NUL-ended)
 * for the arguments args, run from tests/; its exit status as pclose gives
 * it, -1 when it could not be run. */
int generator_output(const char *args, char *out, size_t size);

#endif
