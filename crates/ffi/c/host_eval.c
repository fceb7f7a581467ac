/* host_eval: evaluate a model blob on a measurement CSV through the C API, as `tcomp eval` does.
 *
 *   host_eval MODEL.tcm RUN.csv [GAP_S]
 *
 * Prints `key=value` lines: samples, the raw and residual std and rms, max |residual|, input
 * faults, out-of-range samples and gaps. `cargo xtask ci` (host-tools/xtask/src/ffi.rs) runs it
 * on a blob fitted by `tcomp fit` and a run with a logger dropout, and requires every figure to be
 * bit-for-bit the one `tcomp eval --json` reports.
 *
 * What is tcomp's and what is this program's: each sample is one tcomp_step_dt call (the core's
 * compensator, through libtcomp_ffi.a). The rest is what any host program around it does, done
 * the way `tcomp eval` does it so the figures can be compared exactly:
 *  - the column roles (time, target, reference or constant reference, inputs) come from the blob
 *    (tcomp_channel_meta, tcomp_channel_input_name); cells are parsed as doubles (strtod and
 *    Rust's parser both round correctly) and given to the core as floats;
 *  - dt is the difference of consecutive times, in double, then rounded to float; a step longer
 *    than max(GAP_S, 10 x the median step) is a gap (the sample after it is stepped with gap=1),
 *    the median being the step at rank n/2 of the sorted steps;
 *  - residual = (double)compensated - reference; the figures are Welford's running mean and M2
 *    (population std), the mean square (rms = its square root) and the largest |value|,
 *    accumulated in row order. Build with -ffp-contract=off so no multiply-add is fused.
 * A firmware needs none of this: it knows its period and its missed periods (tcomp_step and
 * tcomp_skip), and sends the compensated values on.
 */
#include "tcomp.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_COLS 64

typedef struct {
    size_t n;
    double mean, m2, sum_sq, max_abs;
} moments;

static void push(moments *m, double x) {
    m->n += 1;
    double d = x - m->mean;
    m->mean += d / (double)m->n;
    m->m2 += d * (x - m->mean);
    m->sum_sq += x * x;
    m->max_abs = fmax(m->max_abs, fabs(x));
}

static double stdev(const moments *m) { return m->n ? sqrt(fmax(m->m2, 0.0) / (double)m->n) : 0.0; }
static double rms(const moments *m) { return sqrt(m->sum_sq / (double)(m->n ? m->n : 1)); }

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The whole file in memory, NUL-terminated. */
static char *slurp(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap);
    for (size_t got; buf && (got = fread(buf + n, 1, cap - n - 1, f)) > 0;) {
        n += got;
        if (cap - n - 1 == 0) buf = realloc(buf, cap *= 2);
    }
    fclose(f);
    if (buf) buf[n] = 0;
    *len = n;
    return buf;
}

/* Splits `line` at commas in place, trimming spaces; returns the number of fields. */
static int split(char *line, char **fields) {
    int n = 0;
    for (char *p = line; n < MAX_COLS;) {
        while (*p == ' ' || *p == '\t') p++;
        fields[n++] = p;
        char *end = strchr(p, ',');
        char *stop = end ? end : p + strlen(p);
        char *q = stop;
        while (q > p && (q[-1] == ' ' || q[-1] == '\t' || q[-1] == '\r')) q--;
        *q = 0;
        if (!end) break;
        p = end + 1;
    }
    return n;
}

static int column(char **names, int n, const char *ptr, size_t len) {
    for (int i = 0; i < n; i++)
        if (strlen(names[i]) == len && memcmp(names[i], ptr, len) == 0) return i;
    return -1;
}

static int fail(const char *what, const char *detail) {
    fprintf(stderr, "host_eval: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    return 1;
}

int main(int argc, char **argv) {
    if (argc < 3) return fail("usage: host_eval MODEL.tcm RUN.csv [GAP_S]", NULL);
    double gap_s = argc > 3 ? strtod(argv[3], NULL) : 0.0;

    /* The blob stays in this buffer for as long as the channel is used: it is borrowed. */
    size_t blob_len = 0;
    char *blob = slurp(argv[1], &blob_len);
    if (!blob) return fail("cannot read", argv[1]);
    static tcomp_channel_t ch; /* TCOMP_CHANNEL_SIZE bytes, aligned by its type */
    int32_t rc = tcomp_load_blob(&ch, (const uint8_t *)blob, blob_len, 1.0f);
    if (rc != TCOMP_OK) {
        char why[160];
        tcomp_channel_describe(&ch, why, sizeof why);
        return fail(tcomp_error_name(rc), why);
    }
    tcomp_meta_t meta;
    tcomp_channel_meta(&ch, &meta);

    size_t csv_len = 0;
    char *csv = slurp(argv[2], &csv_len);
    if (!csv) return fail("cannot read", argv[2]);
    char *save = NULL;
    char *line = strtok_r(csv, "\n", &save);
    if (!line) return fail("empty file", argv[2]);
    char *names[MAX_COLS];
    int n_cols = split(line, names);

    int t_col = column(names, n_cols, meta.time_column.ptr, meta.time_column.len);
    int y_col = column(names, n_cols, meta.target_column.ptr, meta.target_column.len);
    int r_col = meta.reference_column.len
                    ? column(names, n_cols, meta.reference_column.ptr, meta.reference_column.len)
                    : -2;
    int n_in = tcomp_channel_input_count(&ch);
    int in_col[TCOMP_MAX_INPUTS];
    for (int i = 0; i < n_in; i++) {
        char name[64];
        tcomp_channel_input_name(&ch, (size_t)i, name, sizeof name);
        in_col[i] = column(names, n_cols, name, strlen(name));
        if (in_col[i] < 0) return fail("no column for input", name);
    }
    if (t_col < 0 || y_col < 0 || r_col == -1) return fail("a role's column is missing", NULL);

    /* The rows as doubles. */
    size_t cap = 1024, rows = 0;
    double *cells = malloc(cap * (size_t)n_cols * sizeof *cells);
    for (char *l; (l = strtok_r(NULL, "\n", &save)) != NULL;) {
        char *f[MAX_COLS];
        if (split(l, f) != n_cols) return fail("a row has another number of fields", l);
        if (rows == cap) cells = realloc(cells, (cap *= 2) * (size_t)n_cols * sizeof *cells);
        for (int c = 0; c < n_cols; c++) {
            char *end;
            errno = 0;
            cells[rows * (size_t)n_cols + (size_t)c] = strtod(f[c], &end);
            if (end == f[c] || *end) return fail("not a number", f[c]);
        }
        rows++;
    }
#define CELL(r, c) cells[(size_t)(r) * (size_t)n_cols + (size_t)(c)]

    /* Gaps: steps longer than max(GAP_S, 10 x the median step). */
    double median = 1.0;
    if (rows > 1) {
        double *steps = malloc((rows - 1) * sizeof *steps);
        for (size_t i = 1; i < rows; i++) steps[i - 1] = CELL(i, t_col) - CELL(i - 1, t_col);
        qsort(steps, rows - 1, sizeof *steps, cmp_double);
        median = steps[(rows - 1) / 2];
        free(steps);
    }
    double limit = fmax(gap_s, 10.0 * median);

    moments err = {0}, res = {0};
    size_t faults = 0, out_of_range = 0, gaps = 0;
    for (size_t i = 0; i < rows; i++) {
        float inputs[TCOMP_MAX_INPUTS];
        for (int k = 0; k < n_in; k++) inputs[k] = (float)CELL(i, in_col[k]);
        double t = CELL(i, t_col), raw = CELL(i, y_col);
        double ref = r_col >= 0 ? CELL(i, r_col) : (double)meta.reference_value;
        float dt = 1.0f;
        bool gap = false;
        if (i > 0) {
            double d = t - CELL(i - 1, t_col);
            gap = d > limit;
            gaps += gap;
            dt = (float)d;
        }
        tcomp_output_t out;
        rc = tcomp_step_dt(&ch, inputs, (size_t)n_in, dt, gap, (float)raw, &out);
        if (rc != TCOMP_OK) return fail(tcomp_error_name(rc), NULL);
        out_of_range += (out.status & TCOMP_STATUS_OUT_OF_RANGE) != 0;
        faults += (out.status & (TCOMP_STATUS_INPUT_FAULT | TCOMP_STATUS_MODEL_FAULT)) != 0;
        push(&err, raw - ref);
        push(&res, (double)out.compensated - ref);
    }

    printf("samples=%zu\n", res.n);
    printf("raw_std=%.17g\n", stdev(&err));
    printf("residual_std=%.17g\n", stdev(&res));
    printf("raw_rms=%.17g\n", rms(&err));
    printf("residual_rms=%.17g\n", rms(&res));
    printf("max_abs_residual=%.17g\n", res.max_abs);
    printf("input_faults=%zu\n", faults);
    printf("out_of_range=%zu\n", out_of_range);
    printf("gaps=%zu\n", gaps);
    free(cells);
    free(csv);
    free(blob);
    return 0;
}
