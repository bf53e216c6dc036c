/* Runs the fuzz harness (fuzz_scene.c) on files, as libFuzzer replays an input: for make
 * check (tests/test_fuzz_replay.sh), built with the project's compiler from the sources that
 * scripts/fuzz.sh links (tests/fuzz/sources), so that a list gone stale fails at once, and the
 * harness's contract (a load succeeds without messages or fails with one of its statuses and
 * a message; anything else aborts) is checked on every deck the tests keep.
 *
 *   build/tests/fuzz_replay FILE...       exit 0, or 1 naming a file it cannot read */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int main(int argc, char **argv)
{
    LLVMFuzzerInitialize(&argc, &argv);
    for (int k = 1; k < argc; k++) {
        FILE *f = fopen(argv[k], "rb");
        uint8_t *data = NULL;
        long size = -1;
        if (f && fseek(f, 0, SEEK_END) == 0 && (size = ftell(f)) >= 0 &&
            fseek(f, 0, SEEK_SET) == 0 && (data = malloc((size_t)size + 1)) &&
            fread(data, 1, (size_t)size, f) == (size_t)size) {
            LLVMFuzzerTestOneInput(data, (size_t)size);
        } else {
            fprintf(stderr, "fuzz_replay: cannot read %s\n", argv[k]);
            free(data);
            if (f)
                fclose(f);
            return 1;
        }
        free(data);
        fclose(f);
    }
    printf("fuzz_replay: %d inputs kept the harness's contract\n", argc - 1);
    return 0;
}
