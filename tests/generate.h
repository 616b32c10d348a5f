/* generate.h - run the generator on a model text from a test. */
#ifndef HBVM_TESTS_GENERATE_H
#define HBVM_TESTS_GENERATE_H

/* Generate `text` as a model (../gen/hbvmgen flags, from tests/) in a fresh
 * directory, removed afterwards; returns the generated C source (malloc'd,
 * up to 4 MiB) or NULL when the generator fails. */
char *generate_source(const char *text, const char *flags);

/* The contents of a file (malloc'd, NUL-terminated), or NULL. */
char *read_text(const char *path);

/* The number of temporaries ("const double t") in the kernel whose
 * definition starts at the first occurrence of `head` ("_sweep(") in src. */
int kernel_temporaries(const char *src, const char *head);

#endif
