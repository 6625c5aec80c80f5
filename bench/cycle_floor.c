/* The machine's own floor for bench/jitter.py: a cycle that does nothing, in C.
 *
 * One thread per processor, each bound to its processor and SCHED_FIFO at the priority
 * given (bench/jitter.py: above the CPU's scan thread, so that no scan delays it; none if
 * the system refuses), sleeps to absolute
 * deadlines CYCLE_US apart (clock_nanosleep, CLOCK_MONOTONIC; bench/jitter.py: 1000) and
 * stamps each wake-up (up to 2^18 a processor: 262 s at 1 ms); the
 * memory kept out of transparent huge pages as the CPU's is. Between a "start" and an "end"
 * line on stdin they keep the stamps; after "end" it prints them (CLOCK_MONOTONIC
 * nanoseconds, the clock of Python's perf_counter_ns), a list per processor, as one JSON
 * line: {"realtime": 0|1, "starts": [[...], ...]}. A late wake-up here is the machine's
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
#include <unistd.h>

#ifndef PR_SET_THP_DISABLE
#define PR_SET_THP_DISABLE 41
#endif

#define MAX_CPUS 64

static volatile int recording = 0;
static volatile int done = 0;
static const long capacity = 1L << 18;
static long cycle_ns;
static int priority;
static int realtime = 1;

struct floor {
    int cpu;
    long count;
    long long *stamps;
};

static long long now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1000000000LL + t.tv_nsec;
}

static void *loop(void *arg) {
    struct floor *f = arg;
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(f->cpu, &set);
    pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    struct sched_param sp = {.sched_priority = priority};
    if (!(priority > 0 && pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0))
        realtime = 0;
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    while (!done) {
        long long t = now_ns();
        if (recording && f->count < capacity) f->stamps[f->count++] = t;
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
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    if (cpus < 1) cpus = 1;
    if (cpus > MAX_CPUS) cpus = MAX_CPUS;
    if (cycle_ns <= 0) return 2;
    static struct floor floors[MAX_CPUS];
    pthread_t threads[MAX_CPUS];
    for (long i = 0; i < cpus; i++) {
        floors[i].cpu = (int)i;
        floors[i].stamps = malloc(capacity * sizeof(long long));
        if (floors[i].stamps == NULL) return 2;
        if (pthread_create(&threads[i], NULL, loop, &floors[i]) != 0) return 2;
    }
    char line[64];
    while (fgets(line, sizeof line, stdin)) {
        if (strncmp(line, "start", 5) == 0) recording = 1;
        if (strncmp(line, "end", 3) == 0) break;
    }
    recording = 0;
    done = 1;
    for (long i = 0; i < cpus; i++) pthread_join(threads[i], NULL);
    printf("{\"realtime\": %d, \"starts\": [", realtime);
    for (long i = 0; i < cpus; i++) {
        printf("%s[", i ? "," : "");
        for (long k = 0; k < floors[i].count; k++)
            printf("%s%lld", k ? "," : "", floors[i].stamps[k]);
        printf("]");
    }
    printf("]}\n");
    return 0;
}
