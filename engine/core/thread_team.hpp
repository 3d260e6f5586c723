#pragma once

namespace deli {

// The threads that run deli's parallel loops (core/parallel.hpp): the calling thread as
// thread 0, and threads kept between calls that wait for work by spinning, then, after a
// while without any (output, setup), asleep. Not OpenMP's parallel regions: libgomp ends
// every barrier, two a region, with a futex system call whether or not a thread sleeps (the
// rigid melt: nine a step; without them its two-thread loop took 0.464 s for 1000 steps
// against 0.474, the 32000-sphere fluid's 0.819 s for 300 against 0.859: bench/README.md,
// "Stop 40"). Here a loop that finds its threads awake makes no system call.
using TeamJob = void (*)(void* context, int thread, int threads);

// Runs job(context, t, threads) for t = 0..threads-1, t = 0 on the calling thread, and
// returns once every one has returned. Only the workers 1..threads-1 are handed the job: a
// loop of two chunks on a team grown to sixteen threads leaves fourteen waiting, asleep after
// a while, rather than waking each to acknowledge it. The job must not throw. Called from within a
// job (or with threads <= 1), it runs job(context, 0, 1) on the calling thread alone.
void run_on_team(int threads, TeamJob job, void* context);

// Within a job: returns once every thread of the job has called it (spinning). Outside one,
// or in a job of one thread, at once.
void team_barrier();

// The calling thread's number within the running job (0 outside one).
int team_thread();

// The CPUs this process may run on (its affinity mask, which OpenMP's default thread count
// counts too), taken once. A job of more threads waits without spinning.
int cpus_available();
// How many times the team found other processes' threads holding its CPUs and waited
// without spinning for a second (thread_team.cpp), since the process started.
long long crowded_spells();

// run_on_team() with a callable: job(thread, threads).
template <class Job>
void run_on_team(int threads, Job& job) {
  run_on_team(
      threads,
      [](void* context, int thread, int count) { (*static_cast<Job*>(context))(thread, count); },
      &job);
}

}  // namespace deli
