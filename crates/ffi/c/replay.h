/* replay.h: the replay of replay.c and what it needs from the platform it runs on. */
#ifndef TCOMP_REPLAY_H
#define TCOMP_REPLAY_H

#include <stddef.h>
#include <stdint.h>

typedef struct {
    /* Writes a NUL-terminated line (stdout on the host, semihosting on the target). */
    void (*write)(const char *text);
    /* A tick counter (SysTick on the target, 0 on the host) ... */
    uint32_t (*ticks)(void);
    /* ... and the ticks from `t0` to `t1`. */
    uint32_t (*elapsed)(uint32_t t0, uint32_t t1);
    /* The deepest the stack has been so far, in bytes (0 where it is not measured). */
    uint32_t (*stack_peak)(void);
} replay_platform_t;

/* Runs the vector `v` (`len` bytes); nonzero when every output matched. */
int replay(const uint8_t *v, size_t len, const replay_platform_t *p);

#endif
