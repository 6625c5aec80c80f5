/* The machine's own floor for bench/jitter.py: a cycle that does nothing, in C.
 *
 * One thread, SCHED_FIFO at the priority given (as the CPU's scan thread; none if the
 * system refuses), sleeps to absolute deadlines CYCLE_US apart (clock_nanosleep,
 * CLOCK_MONOTONIC) and stamps each wake-up; its memory kept out of transparent huge pages
 * as the CPU's is. Between a "start" and an "end" line on stdin it keeps the stamps; after
 * "end" it prints them (CLOCK_MONOTONIC nanoseconds, the clock of Python's perf_counter_ns)
 * as one JSON line: {"starts": [...], "realtime": 0|1}. A late wake-up here is the machine's
 * (the kernel, the hypervisor), not the interpreter's.
 *
 * usage: cycle_floor CYCLE_US PRIORITY
 */
#define _GNU_SOURCE
#include <pthread.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <time.h>

#ifndef PR_SET_THP_DISABLE
#define PR_SET_THP_DISABLE 41
#endif

static volatile int recording = 0;
static volatile int done = 0;
static long long *stamps;
static long count = 0;
static const long capacity = 1L << 20;
static long cycle_ns;
static int priority;
static int realtime = 0;

static long long now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1000000000LL + t.tv_nsec;
}

static void *loop(void *arg) {
    (void)arg;
    struct sched_param sp = {.sched_priority = priority};
    realtime = priority > 0 && pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    while (!done) {
        long long t = now_ns();
        if (recording && count < capacity) stamps[count++] = t;
        next.tv_nsec += cycle_ns;
        while (next.tv_nsec >= 1000000000L) {
            next.tv_nsec -= 1000000000L;
            next.tv_sec += 1;
        }
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
    }
    return NULL;
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s CYCLE_US PRIORITY\n", argv[0]);
        return 2;
    }
    cycle_ns = atol(argv[1]) * 1000L;
    priority = atoi(argv[2]);
    prctl(PR_SET_THP_DISABLE, 1, 0, 0, 0);
    stamps = malloc(capacity * sizeof *stamps);
    if (stamps == NULL || cycle_ns <= 0) return 2;
    pthread_t thread;
    if (pthread_create(&thread, NULL, loop, NULL) != 0) return 2;
    char line[64];
    while (fgets(line, sizeof line, stdin)) {
        if (strncmp(line, "start", 5) == 0) recording = 1;
        if (strncmp(line, "end", 3) == 0) break;
    }
    recording = 0;
    done = 1;
    pthread_join(thread, NULL);
    printf("{\"realtime\": %d, \"starts\": [", realtime);
    for (long i = 0; i < count; i++) printf("%s%lld", i ? "," : "", stamps[i]);
    printf("]}\n");
    return 0;
}
