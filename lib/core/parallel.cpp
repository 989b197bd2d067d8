#include "core/parallel.h"

#include <sched.h>

#include "core/stop.h"

namespace rs {

// The CPUs this process may run on: all of them, or fewer under taskset, a cgroup's cpuset or
// mpirun's binding (a rank bound to one core gets one thread, not all of the machine's).
int ThreadPool::hardwareThreads() {
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
    return int(std::max(1u, std::thread::hardware_concurrency()));
}

ThreadPool::ThreadPool(int threads) {
    int n = threads > 0 ? threads : hardwareThreads();
    for (int t = 1; t < n; ++t) workers_.emplace_back([this, t] { workerLoop(t); });
}

ThreadPool::~ThreadPool() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& w : workers_) w.join();
}

void ThreadPool::runChunks(int thread) {
    for (;;) {
        int64_t begin = next_.fetch_add(chunk_);
        if (begin >= n_ || failed_.load(std::memory_order_relaxed)) return;
        try {
            throwIfStopped();
            (*fn_)(begin, std::min(begin + chunk_, n_), thread);
        } catch (...) {
            std::lock_guard<std::mutex> lock(mutex_);
            if (!error_) error_ = std::current_exception();
            failed_ = true;
        }
    }
}

void ThreadPool::workerLoop(int thread) {
    uint64_t seen = 0;
    for (;;) {
        {
            std::unique_lock<std::mutex> lock(mutex_);
            wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
            if (stop_) return;
            seen = generation_;
        }
        runChunks(thread);
        {
            std::lock_guard<std::mutex> lock(mutex_);
            --busy_;
        }
        done_.notify_all();
    }
}

void ThreadPool::parallelFor(int64_t n, int64_t chunk, const ChunkFn& fn) {
    if (n <= 0) return;
    chunk = std::max<int64_t>(chunk, 1);
    if (workers_.empty() || n <= chunk) {
        for (int64_t b = 0; b < n; b += chunk) {
            throwIfStopped();
            fn(b, std::min(b + chunk, n), 0);
        }
        return;
    }
    {
        std::lock_guard<std::mutex> lock(mutex_);
        fn_ = &fn;
        n_ = n;
        chunk_ = chunk;
        next_ = 0;
        error_ = nullptr;
        failed_ = false;
        busy_ = int(workers_.size());
        ++generation_;
    }
    wake_.notify_all();
    runChunks(0);
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return busy_ == 0; });
    fn_ = nullptr;
    if (error_) std::rethrow_exception(error_);
}

}  // namespace rs
