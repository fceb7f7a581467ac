/* replay_host: replay.c on the host, reading the vector from a file. Its output is the one the
 * bare-metal run under QEMU (mps2/startup.c) must print, hash for hash. */
#include "replay.h"

#include <stdio.h>
#include <stdlib.h>

static void write_stdout(const char *text) { fputs(text, stdout); }
static uint32_t no_ticks(void) { return 0; }
static uint32_t no_elapsed(uint32_t t0, uint32_t t1) { return t1 - t0; }
static uint32_t no_stack(void) { return 0; }

int main(int argc, char **argv) {
    if (argc != 2) {
        fputs("usage: replay_host VECTOR.bin\n", stderr);
        return 2;
    }
    FILE *f = fopen(argv[1], "rb");
    if (!f) {
        perror(argv[1]);
        return 2;
    }
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *v = malloc(len > 0 ? (size_t)len : 1);
    if (!v || fread(v, 1, (size_t)len, f) != (size_t)len) {
        fputs("replay_host: cannot read the vector\n", stderr);
        return 2;
    }
    fclose(f);
    replay_platform_t p = {write_stdout, no_ticks, no_elapsed, no_stack};
    int ok = replay(v, (size_t)len, &p);
    free(v);
    return ok ? 0 : 1;
}
