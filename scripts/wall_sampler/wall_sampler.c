// Wall-clock sampler of a program's main thread, for machines without perf or nsys (the GPU
// machine's image has neither): preloaded, it signals the thread that loads it (the main
// thread) every WPROF_US microseconds of CLOCK_MONOTONIC (default 1000) and records its stack
// (backtrace, 14 frames), so time spent waiting (a stream synchronise, a lock, I/O) is sampled
// too; at exit the stacks and /proc/self/maps go to WPROF_OUT. Symbolise on any machine that
// holds the same program files with scripts/wall_sampler/symbolise.py.
// Build: gcc -shared -fPIC -O2 -o libwall_sampler.so scripts/wall_sampler/wall_sampler.c -lrt
// Run:   WPROF_OUT=samples.txt LD_PRELOAD=./libwall_sampler.so PROGRAM ARGS...
// (docs/benchmarks_log.md, "The session of 2026-12-07, day", shows a use.)
#define _GNU_SOURCE
#include <execinfo.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>
#define MAXS 200000
#define DEPTH 14
static void* buf[MAXS][DEPTH];
static int depth[MAXS];
static volatile int n = 0;
static timer_t tid;
static void handler(int sig) {
  (void)sig;
  int i = n;
  if (i >= MAXS) return;
  depth[i] = backtrace(buf[i], DEPTH);
  n = i + 1;
}
__attribute__((constructor)) static void start(void) {
  const char* us = getenv("WPROF_US");
  if (!getenv("WPROF_OUT")) return;
  void* warm[4];
  backtrace(warm, 4);
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = handler;
  sa.sa_flags = SA_RESTART;
  sigaction(SIGRTMIN + 3, &sa, NULL);
  struct sigevent sev;
  memset(&sev, 0, sizeof sev);
  sev.sigev_notify = SIGEV_THREAD_ID;
  sev.sigev_signo = SIGRTMIN + 3;
  sev._sigev_un._tid = (pid_t)syscall(SYS_gettid);
  if (timer_create(CLOCK_MONOTONIC, &sev, &tid) != 0) return;
  long p = us ? atol(us) : 1000;
  struct itimerspec its = {{p / 1000000, (p % 1000000) * 1000},
                           {p / 1000000, (p % 1000000) * 1000}};
  timer_settime(tid, 0, &its, NULL);
}
__attribute__((destructor)) static void stop(void) {
  const char* path = getenv("WPROF_OUT");
  if (!path) return;
  timer_delete(tid);
  FILE* f = fopen(path, "w");
  if (!f) return;
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < depth[i]; ++d) fprintf(f, "%p ", buf[i][d]);
    fprintf(f, "\n");
  }
  fprintf(f, "MAPS\n");
  FILE* m = fopen("/proc/self/maps", "r");
  char line[512];
  while (m && fgets(line, sizeof line, m)) fputs(line, f);
  if (m) fclose(m);
  fclose(f);
}
