// A worker thread with a bounded job queue (background_jobs.hpp).
#include <sflsh/core/background_jobs.hpp>

#include <sflsh/core/error.hpp>

#include <chrono>

namespace sflsh {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
}  // namespace

BackgroundJobs::BackgroundJobs(std::size_t capacity) : capacity_(capacity) {
  require(capacity >= 1, "background jobs: the queue needs a capacity of at least 1");
  worker_ = std::thread([this] { work(); });
}

BackgroundJobs::~BackgroundJobs() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
    queue_.clear();
  }
  changed_.notify_all();
  worker_.join();
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
  changed_.wait(lock, [&] { return (queue_.empty() && !running_job_) || error_; });
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
    running_job_ = true;
    lock.unlock();
    changed_.notify_all();   // a slot is free
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
    running_job_ = false;
    if (error && !error_) {
      error_ = error;
      queue_.clear();
    }
    changed_.notify_all();
  }
}

}  // namespace sflsh
