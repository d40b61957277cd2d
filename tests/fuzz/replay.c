/*
 * replay.c -- the fuzz corpus (tests/fuzz/corpus) run through fuzz_lib.c's
 * harness without libFuzzer or sanitizers: every input once, in name order,
 * under the same contracts (the harness aborts on a violation).  Built with
 * the host compiler against the project's library, so it runs in every
 * build, and in `make coverage` (instrumented library) the corpus's rare
 * paths count: inputs that only a fuzzer found worth keeping, such as
 * tile sets whose tiles disagree on a seam.
 *   corpus_replay <dir>...
 */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);

static int by_name(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

int main(int argc, char **argv)
{
    static uint8_t buf[1 << 16]; /* the harness reads at most 512 bytes of an input */
    long inputs = 0;
    int a;
    for (a = 1; a < argc; ++a) {
        DIR *dir = opendir(argv[a]);
        struct dirent *e;
        char **names = NULL;
        size_t count = 0, cap = 0, k;
        if (dir == NULL) {
            fprintf(stderr, "corpus_replay: %s: cannot open the directory\n", argv[a]);
            return 1;
        }
        while ((e = readdir(dir)) != NULL) {
            if (e->d_name[0] == '.') {
                continue;
            }
            if (count == cap) {
                cap = cap ? 2 * cap : 64;
                names = realloc(names, cap * sizeof *names);
                if (names == NULL) {
                    fprintf(stderr, "corpus_replay: out of memory\n");
                    return 1;
                }
            }
            names[count] = malloc(strlen(argv[a]) + strlen(e->d_name) + 2);
            if (names[count] == NULL) {
                fprintf(stderr, "corpus_replay: out of memory\n");
                return 1;
            }
            sprintf(names[count], "%s/%s", argv[a], e->d_name);
            count++;
        }
        closedir(dir);
        qsort(names, count, sizeof *names, by_name);
        for (k = 0; k < count; ++k) {
            FILE *f = fopen(names[k], "rb");
            size_t n;
            if (f == NULL) {
                fprintf(stderr, "corpus_replay: %s: cannot open\n", names[k]);
                return 1;
            }
            n = fread(buf, 1, sizeof buf, f);
            fclose(f);
            printf("%s (%zu bytes)\n", names[k], n);
            fflush(stdout); /* an abort names the input */
            LLVMFuzzerTestOneInput(buf, n);
            inputs++;
            free(names[k]);
        }
        free(names);
    }
    printf("corpus_replay: %ld inputs, every contract held\n", inputs);
    return inputs > 0 ? 0 : 1;
}
