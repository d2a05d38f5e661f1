#pragma once
// Worker threads that run submitted jobs (e.g. writing frame files while the solver goes on; with one worker
// in submission order, with several in any order),
// with a bounded queue: submit() waits while `capacity` jobs are pending, so a slow disk slows the producer
// down instead of filling the memory. The first job that throws stops the worker: the pending jobs are
// dropped and the exception is rethrown by the next submit() or by wait(). The destructor drops pending jobs
// and joins, so a failing run stops its writes before its run folder (run_folder.hpp) is removed.
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace sflsh {

class BackgroundJobs {
 public:
  /// capacity ≥ 1: pending jobs (not counting the running ones) before submit() waits; workers ≥ 1 threads.
  explicit BackgroundJobs(std::size_t capacity, int workers = 1);
  ~BackgroundJobs();
  BackgroundJobs(const BackgroundJobs&) = delete;
  BackgroundJobs& operator=(const BackgroundJobs&) = delete;

  /// Queues a job; waits while the queue is full. Rethrows the error of an earlier job.
  void submit(std::function<void()> job);
  /// Waits until every submitted job has run; rethrows the first job error.
  void wait();

  /// Seconds the workers spent running jobs (summed), and seconds submit()/wait() waited for them (caller's thread).
  double busy_seconds() const;
  double waited_seconds() const { return waited_seconds_; }

 private:
  void work();
  void rethrow_error_locked();

  std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::function<void()>> queue_;
  int running_jobs_ = 0;
  bool stopping_ = false;
  std::exception_ptr error_;
  double busy_seconds_ = 0.0;
  double waited_seconds_ = 0.0;
  std::vector<std::thread> workers_;
};

}  // namespace sflsh
