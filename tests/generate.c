/* generate.c - run the generator on a model text from a test (generate.h). */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "generate.h"

#define MAX_SOURCE (4 << 20)

char *read_text(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  char *s = calloc(1, MAX_SOURCE + 1);
  if (s && fread(s, 1, MAX_SOURCE, f) == 0 && ferror(f)) {
    free(s);
    s = NULL;
  }
  fclose(f);
  return s;
}

char *generate_source(const char *text, const char *flags) {
  char dir[] = "/tmp/hbvm-test-XXXXXX", path[256], cmd[512];
  if (!mkdtemp(dir)) return NULL;
  snprintf(path, sizeof path, "%s/model.ham", dir);
  FILE *f = fopen(path, "w");
  char *src = NULL;
  if (f) {
    fputs(text, f);
    fclose(f);
    snprintf(cmd, sizeof cmd, "../gen/hbvmgen %s -o %s %s", flags, dir, path);
    if (system(cmd) == 0) {
      snprintf(path, sizeof path, "%s/model.c", dir);
      src = read_text(path);
    }
  }
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  if (system(cmd) != 0) fprintf(stderr, "generate_source: could not remove %s\n", dir);
  return src;
}

int kernel_temporaries(const char *src, const char *head) {
  const char *p = strstr(src, head);
  const char *end = p ? strstr(p, "\n}\n") : NULL;
  int n = 0;
  while (p && (p = strstr(p + 1, "const double t")) && p < end) n++;
  return n;
}

int generator_output(const char *args, char *out, size_t size) {
  char cmd[1024];
  snprintf(cmd, sizeof cmd, "../gen/hbvmgen %s 2>&1", args);
  FILE *f = popen(cmd, "r");
  if (!f) return -1;
  size_t n = fread(out, 1, size - 1, f);
  out[n] = 0;
  return pclose(f);
}
