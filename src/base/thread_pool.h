// The process's pool of worker threads that batches of worlds are shared out over.
//
// One pool per process, started at the first batched step: size() - 1 workers plus the
// calling thread, which always takes a share (a single world runs on it alone). The size is
// the number of cores this process may use, at most RIGID_GYM_NUM_THREADS when that is set,
// or what set_size() asked for. A child made by fork() has none of its parent's threads, so
// the child forgets the parent's pool (without touching its locks, which a worker may have
// held at the fork) and starts its own at its first batched step.
#pragma once

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace rg {

class ThreadPool {
public:
    // The pool of this process (made, or made again after a fork, on first use).
    static ThreadPool& instance();

    // Threads a batch is shared out over, the calling thread included (>= 1).
    static int default_size();
    static void set_size(int threads);

    int size() const { return size_; }

    // job(i) for every i in [0, jobs), spread over the workers and the calling thread;
    // returns when all are done. An exception thrown by a job is rethrown here. Calls from
    // several threads take turns. set_size() must not be called while a batch runs.
    void run(int jobs, const std::function<void(int)>& job);

    ~ThreadPool();

private:
    explicit ThreadPool(int size);
    void work();
    void take_jobs();

    int size_;
    std::vector<std::thread> workers_;
    std::mutex batch_mutex_;  // held for a whole run()
    std::mutex mutex_;        // guards the fields below
    std::condition_variable wake_, finished_;
    const std::function<void(int)>* job_ = nullptr;
    int jobs_ = 0, next_ = 0, running_ = 0;
    long generation_ = 0;
    bool stopping_ = false;
    std::exception_ptr error_;
};

}  // namespace rg
