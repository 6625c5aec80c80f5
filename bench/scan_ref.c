/* The scan benchmark's workload in plain C, for a floor to compare against (bench/scan.py).
 *
 * 200 sequencers, each a loop of 25 steps; every step runs "S1 N c := 0; N c := c + 1;",
 * "D Mb.d, T#20MS; L Mb.l, T#20MS;" and leaves on "c >= p" (p = 2 + g % 3). Each scan walks
 * every step of every sequencer, the way matiec-generated code walks an SFC: first the
 * transitions of the active steps (on the state at the start of the scan), then the
 * actions of the active steps. Built as a shared library and called through ctypes, so its
 * scans interleave with the Python workloads in one run.
 */
#include <stdint.h>
#include <string.h>
#include <time.h>

#define N_SEQ 200
#define STEPS 25
#define CYCLE_MS 10
#define D_MS 20
#define L_MS 20

static uint8_t x[N_SEQ][STEPS];        /* step active */
static int32_t since_ms[N_SEQ][STEPS]; /* activation time */
static int16_t c[N_SEQ];
static uint8_t markers[N_SEQ / 4];
static int32_t now_ms;

static int64_t ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

static void act(int g, int k) {
    int32_t elapsed = now_ms - since_ms[g][k];
    int byte = g / 4, bit = g % 4;
    uint8_t d_mask = (uint8_t)(1u << (2 * bit)), l_mask = (uint8_t)(1u << (2 * bit + 1));
    uint8_t v = markers[byte] & (uint8_t)~(d_mask | l_mask);
    c[g] += 1;
    if (elapsed >= D_MS) v |= d_mask;
    if (elapsed < L_MS) v |= l_mask;
    markers[byte] = v;
}

void ref_start(void) {
    memset(x, 0, sizeof x);
    memset(since_ms, 0, sizeof since_ms);
    memset(c, 0, sizeof c);
    memset(markers, 0, sizeof markers);
    now_ms = 0;
    for (int g = 0; g < N_SEQ; g++) { /* the startup call: initial steps, their rows once */
        x[g][0] = 1;
        act(g, 0);
    }
}

/* Run n scans; store each scan's wall time (ns) in out[0..n-1]. */
void ref_scan(int n, int64_t *out) {
    for (int s = 0; s < n; s++) {
        int64_t t0 = ns();
        now_ms += CYCLE_MS;
        for (int g = 0; g < N_SEQ; g++) {
            int p = 2 + g % 3, fired = -1;
            for (int k = 0; k < STEPS; k++)
                if (x[g][k] && c[g] >= p) fired = k;
            if (fired >= 0) {
                int nxt = (fired + 1) % STEPS;
                x[g][fired] = 0;
                x[g][nxt] = 1;
                since_ms[g][nxt] = now_ms;
                c[g] = 0;
            }
            for (int k = 0; k < STEPS; k++)
                if (x[g][k]) act(g, k);
        }
        out[s] = ns() - t0;
    }
}

/* The step (0..24) each sequencer is in, and the D/L marker bytes, for the final check. */
void ref_positions(int32_t *pos, uint8_t *mk) {
    for (int g = 0; g < N_SEQ; g++)
        for (int k = 0; k < STEPS; k++)
            if (x[g][k]) pos[g] = k;
    memcpy(mk, markers, sizeof markers);
}
