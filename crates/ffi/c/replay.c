/* replay.c: runs a replay vector through the C API, the same source on the host (replay_host.c)
 * and on the bare-metal Cortex-M4F (mps2/startup.c), so the two can be compared bit for bit.
 *
 * Vector layout (little-endian, written by host-tools/xtask/src/ffi.rs):
 *   0   "TCRV"          magic
 *   4   u32 version     1
 *   8   u32 samples     n
 *   12  u32 inputs      k (model input columns per sample)
 *   16  u32 mode        0: tcomp_step at the period (a flagged record was preceded by dt seconds
 *                       of missed periods: tcomp_skip(dt)); 1: tcomp_step_dt(dt, gap flag)
 *   20  f32 period_s
 *   24  u32 blob_len    then the blob, padded with zeros to a multiple of 4
 *   ..  n records of k+3 words: k inputs f32, raw f32, dt f32, flags u32 (bit 0: gap / skip)
 *   ..  n expected outputs of 3 words, computed on the host by the Rust core's Channel:
 *       compensated f32, correction f32, status u32
 *
 * Prints (through the platform's `write`):
 *   REPLAY samples=N mismatches=M first_mismatch=I hash=H ticks_total=T ticks_max=X stack_peak=S
 *   REPLAY-CHECKS corrupt_blob=<error name> status=<names> stack_peak_validate=V
 *   REPLAY OK | REPLAY FAIL
 * H is FNV-1a 64 over every output's bytes (compensated, correction, status as 4 LE bytes
 * each): equal hashes on host and target mean bit-identical outputs. T and X are the
 * platform's tick counts around each step call, S the deepest the stack went while loading and
 * stepping, V the same after a tcomp_validate_blob (which decodes on the stack), bytes (all 0 on
 * the host).
 */
#include "replay.h"

#include "tcomp.h"

static uint32_t u32_at(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float f32_at(const uint8_t *p) {
    uint32_t bits = u32_at(p);
    float f;
    __builtin_memcpy(&f, &bits, 4);
    return f;
}

static uint32_t bits_of(float f) {
    uint32_t b;
    __builtin_memcpy(&b, &f, 4);
    return b;
}

/* A tiny formatter: no printf on the bare-metal side. */
typedef struct {
    char buf[256];
    unsigned len;
} line_t;

static void put(line_t *l, const char *s) {
    while (*s && l->len + 1 < sizeof l->buf) l->buf[l->len++] = *s++;
    l->buf[l->len] = 0;
}

static void put_u64(line_t *l, uint64_t v) {
    char tmp[21];
    int i = 20;
    tmp[i] = 0;
    do {
        tmp[--i] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    put(l, tmp + i);
}

static void put_i64(line_t *l, int64_t v) {
    if (v < 0) {
        put(l, "-");
        put_u64(l, (uint64_t)(-(v + 1)) + 1);
    } else {
        put_u64(l, (uint64_t)v);
    }
}

static void put_hex64(line_t *l, uint64_t v) {
    char tmp[19] = "0x";
    for (int i = 0; i < 16; i++) tmp[2 + i] = "0123456789abcdef"[(v >> (60 - 4 * i)) & 0xF];
    tmp[18] = 0;
    put(l, tmp);
}

static uint64_t fnv(uint64_t h, uint32_t word) {
    for (int i = 0; i < 4; i++) {
        h ^= (word >> (8 * i)) & 0xFF;
        h *= 0x100000001b3ull;
    }
    return h;
}

int replay(const uint8_t *v, size_t len, const replay_platform_t *p) {
    line_t l = {{0}, 0};
    if (len < 28 || u32_at(v) != 0x56524354u /* "TCRV" */ || u32_at(v + 4) != 1) {
        p->write("REPLAY FAIL: not a replay vector\n");
        return 0;
    }
    uint32_t n = u32_at(v + 8), k = u32_at(v + 12), mode = u32_at(v + 16);
    float period = f32_at(v + 20);
    uint32_t blob_len = u32_at(v + 24);
    const uint8_t *blob = v + 28;
    const uint8_t *records = blob + ((blob_len + 3u) & ~3u);
    const uint8_t *expected = records + (size_t)n * 4u * (k + 3u);
    if (k > TCOMP_MAX_INPUTS || (size_t)(expected - v) + (size_t)n * 12u > len) {
        p->write("REPLAY FAIL: vector too short\n");
        return 0;
    }

    static tcomp_channel_t ch; /* a static, as a firmware keeps its channels */
    int32_t rc = tcomp_load_blob(&ch, blob, blob_len, period);
    if (rc != TCOMP_OK) {
        char why[160];
        tcomp_channel_describe(&ch, why, sizeof why);
        put(&l, "REPLAY FAIL: ");
        put(&l, tcomp_error_name(rc));
        put(&l, ": ");
        put(&l, why);
        put(&l, "\n");
        p->write(l.buf);
        return 0;
    }
    if ((uint32_t)tcomp_channel_input_count(&ch) != k) {
        p->write("REPLAY FAIL: the vector's input count is not the model's\n");
        return 0;
    }

    uint64_t hash = 0xcbf29ce484222325ull, ticks_total = 0;
    uint32_t mismatches = 0, ticks_max = 0;
    int64_t first_mismatch = -1;
    for (uint32_t i = 0; i < n; i++) {
        const uint8_t *r = records + (size_t)i * 4u * (k + 3u);
        float inputs[TCOMP_MAX_INPUTS];
        for (uint32_t j = 0; j < k; j++) inputs[j] = f32_at(r + 4 * j);
        float raw = f32_at(r + 4 * k), dt = f32_at(r + 4 * k + 4);
        uint32_t flags = u32_at(r + 4 * k + 8);
        tcomp_output_t out;
        uint32_t t0, t1;
        if (mode == 0) {
            if (flags & 1) tcomp_skip(&ch, dt);
            t0 = p->ticks();
            rc = tcomp_step(&ch, inputs, k, raw, &out);
            t1 = p->ticks();
        } else {
            t0 = p->ticks();
            rc = tcomp_step_dt(&ch, inputs, k, dt, (flags & 1) != 0, raw, &out);
            t1 = p->ticks();
        }
        uint32_t spent = p->elapsed(t0, t1);
        ticks_total += spent;
        if (spent > ticks_max) ticks_max = spent;
        const uint8_t *e = expected + (size_t)i * 12u;
        uint32_t c = bits_of(out.compensated), x = bits_of(out.correction), s = out.status;
        if (rc != TCOMP_OK || c != u32_at(e) || x != u32_at(e + 4) || s != u32_at(e + 8)) {
            if (first_mismatch < 0) first_mismatch = i;
            mismatches++;
        }
        hash = fnv(fnv(fnv(hash, c), x), s);
    }

    put(&l, "REPLAY samples=");
    put_u64(&l, n);
    put(&l, " mismatches=");
    put_u64(&l, mismatches);
    put(&l, " first_mismatch=");
    put_i64(&l, first_mismatch);
    put(&l, " hash=");
    put_hex64(&l, hash);
    put(&l, " ticks_total=");
    put_u64(&l, ticks_total);
    put(&l, " ticks_max=");
    put_u64(&l, ticks_max);
    put(&l, " stack_peak=");
    put_u64(&l, p->stack_peak());
    put(&l, "\n");
    p->write(l.buf);

    /* The refusals work on this side too: a corrupted copy of the blob is named as corrupt. */
    static uint8_t copy[4096];
    int corrupt_ok = 0;
    if (blob_len <= sizeof copy) {
        __builtin_memcpy(copy, blob, blob_len);
        copy[blob_len / 2] ^= 0x40;
        rc = tcomp_validate_blob(copy, blob_len, NULL, 0);
        corrupt_ok = rc == TCOMP_ERR_BLOB_CHECKSUM;
    }
    char status[160];
    tcomp_status_describe(TCOMP_STATUS_OUT_OF_RANGE | TCOMP_STATUS_INPUT_FAULT, status, sizeof status);
    l.len = 0;
    put(&l, "REPLAY-CHECKS corrupt_blob=");
    put(&l, tcomp_error_name(rc));
    put(&l, " status=");
    put(&l, status);
    put(&l, " stack_peak_validate=");
    put_u64(&l, p->stack_peak());
    put(&l, "\n");
    p->write(l.buf);

    int ok = n > 0 && mismatches == 0 && corrupt_ok;
    p->write(ok ? "REPLAY OK\n" : "REPLAY FAIL\n");
    return ok;
}
