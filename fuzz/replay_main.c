/* SPDX-License-Identifier: MIT */
/* A main() for the fuzz harnesses without libFuzzer: runs LLVMFuzzerTestOneInput once on each
 * file named on the command line (directories: on each file inside, sorted). The regression
 * tests (tests/reliability/CMakeLists.txt) build every harness with this main under gcc and
 * replay the crash inputs kept in tests/reliability/crashes/<harness>/ and the bad-input corpus;
 * a harness oracle or a sanitizer turns a regression into a failing test. */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int run_file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "replay: cannot open %s\n", path);
    return 1;
  }
  size_t cap = 1 << 16, n = 0;
  uint8_t *buf = malloc(cap);
  size_t got;
  while ((got = fread(buf + n, 1, cap - n, f)) > 0) {
    n += got;
    if (n == cap) buf = realloc(buf, cap *= 2);
  }
  fclose(f);
  fprintf(stderr, "replay: %s (%zu bytes)\n", path, n);
  LLVMFuzzerTestOneInput(buf, n);
  free(buf);
  return 0;
}

static int by_name(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

int main(int argc, char **argv) {
  int failures = 0, count = 0;
  for (int i = 1; i < argc; i++) {
    struct stat st;
    if (stat(argv[i], &st) != 0) {
      fprintf(stderr, "replay: no such file or directory: %s\n", argv[i]);
      return 1;
    }
    if (!S_ISDIR(st.st_mode)) {
      failures += run_file(argv[i]);
      count++;
      continue;
    }
    DIR *d = opendir(argv[i]);
    char **names = NULL;
    size_t nn = 0;
    struct dirent *de;
    while (d && (de = readdir(d))) {
      if (de->d_name[0] == '.') continue;
      names = realloc(names, (nn + 1) * sizeof *names);
      names[nn] = malloc(strlen(argv[i]) + strlen(de->d_name) + 2);
      sprintf(names[nn++], "%s/%s", argv[i], de->d_name);
    }
    if (d) closedir(d);
    qsort(names, nn, sizeof *names, by_name);
    for (size_t k = 0; k < nn; k++) {
      if (stat(names[k], &st) == 0 && S_ISREG(st.st_mode)) {
        failures += run_file(names[k]);
        count++;
      }
      free(names[k]);
    }
    free(names);
  }
  printf("replay: %d inputs, none crashed\n", count);
  return failures ? 1 : 0;
}
