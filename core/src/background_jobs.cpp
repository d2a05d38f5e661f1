// A worker thread with a bounded job queue (background_jobs.hpp).
#include <sflsh/core/background_jobs.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>

#include <chrono>

namespace sflsh {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

BackgroundJobs::BackgroundJobs(std::size_t capacity, int workers) : capacity_(capacity) {
  require(capacity >= 1 && workers >= 1, "background jobs: need a capacity and workers of at least 1 (got {}, {})",
          capacity, workers);
  for (int k = 0; k < workers; ++k) workers_.emplace_back([this] { work(); });
}

BackgroundJobs::~BackgroundJobs() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
    queue_.clear();
  }
  changed_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

void BackgroundJobs::rethrow_error_locked() {
  if (error_) std::rethrow_exception(error_);
}

void BackgroundJobs::submit(std::function<void()> job) {
  std::unique_lock lock(mutex_);
  rethrow_error_locked();
  if (queue_.size() >= capacity_) {
    const auto t0 = Clock::now();
    changed_.wait(lock, [&] { return queue_.size() < capacity_ || error_; });
    waited_seconds_ += seconds_since(t0);
    rethrow_error_locked();
  }
  queue_.push_back(std::move(job));
  lock.unlock();
  changed_.notify_all();
}

void BackgroundJobs::wait() {
  std::unique_lock lock(mutex_);
  const auto t0 = Clock::now();
  changed_.wait(lock, [&] { return (queue_.empty() && running_jobs_ == 0) || error_; });
  waited_seconds_ += seconds_since(t0);
  rethrow_error_locked();
}

double BackgroundJobs::busy_seconds() const {
  const std::lock_guard lock(mutex_);
  return busy_seconds_;
}

void BackgroundJobs::work() {
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (stopping_) return;
    std::function<void()> job = std::move(queue_.front());
    queue_.pop_front();
    ++running_jobs_;
    lock.unlock();
    changed_.notify_all();  // a slot is free
    const auto t0 = Clock::now();
    std::exception_ptr error;
    try {
      job();
    } catch (...) {
      error = std::current_exception();
    }
    const double seconds = seconds_since(t0);
    lock.lock();
    busy_seconds_ += seconds;
    --running_jobs_;
    if (error && !error_) {
      error_ = error;
      queue_.clear();
    }
    changed_.notify_all();
  }
}

}  // namespace sflsh
