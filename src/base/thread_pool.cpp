// The worker pool (thread_pool.h).
#include "base/thread_pool.h"

#include <algorithm>
#include <cstdlib>

#if defined(__unix__) || defined(__APPLE__)
#include <pthread.h>
#endif
#if defined(__linux__)
#include <sched.h>
#endif

namespace rg {

namespace {

ThreadPool* current_pool = nullptr;
int requested_size = 0;  // 0: default_size()

#if defined(__unix__) || defined(__APPLE__)
// In a forked child the pool's threads do not exist and its mutex may be locked for ever:
// forget it (its memory is left as it is) so the child starts a pool of its own.
void forget_pool_in_child() { current_pool = nullptr; }

[[maybe_unused]] const bool fork_handler_installed = [] {
    pthread_atfork(nullptr, nullptr, forget_pool_in_child);
    return true;
}();
#endif

int usable_cores() {
#if defined(__linux__)
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof(set), &set) == 0) {
        return std::max(1, CPU_COUNT(&set));
    }
#endif
    return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace

int ThreadPool::default_size() {
    int threads = usable_cores();
    if (const char* limit = std::getenv("RIGID_GYM_NUM_THREADS")) {
        const int value = std::atoi(limit);
        if (value > 0) {
            threads = std::min(threads, value);
        }
    }
    return threads;
}

void ThreadPool::set_size(int threads) {
    requested_size = std::max(threads, 0);
    if (current_pool != nullptr && current_pool->size() != (requested_size > 0 ? requested_size : default_size())) {
        delete current_pool;
        current_pool = nullptr;
    }
}

ThreadPool& ThreadPool::instance() {
    if (current_pool == nullptr) {
        current_pool = new ThreadPool(requested_size > 0 ? requested_size : default_size());
    }
    return *current_pool;
}

ThreadPool::ThreadPool(int size) : size_(std::max(size, 1)) {
    for (int k = 1; k < size_; ++k) {
        workers_.emplace_back([this] { work(); });
    }
}

ThreadPool::~ThreadPool() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stopping_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : workers_) {
        t.join();
    }
}

void ThreadPool::take_jobs() {
    // with mutex_ held on entry and exit
    while (next_ < jobs_) {
        const int i = next_++;
        running_ += 1;
        mutex_.unlock();
        std::exception_ptr failure;
        try {
            (*job_)(i);
        } catch (...) {
            failure = std::current_exception();
        }
        mutex_.lock();
        running_ -= 1;
        if (failure && !error_) {
            error_ = failure;
        }
    }
}

void ThreadPool::work() {
    long seen = 0;
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
        wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
        if (stopping_) {
            return;
        }
        seen = generation_;
        take_jobs();
        if (next_ >= jobs_ && running_ == 0) {
            finished_.notify_all();
        }
    }
}

void ThreadPool::run(int jobs, const std::function<void(int)>& job) {
    if (jobs <= 0) {
        return;
    }
    if (jobs == 1 || workers_.empty()) {
        for (int i = 0; i < jobs; ++i) {
            job(i);
        }
        return;
    }
    std::lock_guard<std::mutex> one_batch(batch_mutex_);  // batches from other threads wait
    std::unique_lock<std::mutex> lock(mutex_);
    job_ = &job;
    jobs_ = jobs;
    next_ = 0;
    running_ = 0;
    error_ = nullptr;
    generation_ += 1;
    wake_.notify_all();
    take_jobs();
    finished_.wait(lock, [&] { return next_ >= jobs_ && running_ == 0; });
    job_ = nullptr;
    if (error_) {
        std::exception_ptr failure = error_;
        error_ = nullptr;
        std::rethrow_exception(failure);
    }
}

}  // namespace rg
