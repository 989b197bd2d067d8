// One thread pool for the whole render. parallelFor hands out fixed-size chunks of an index
// range; which thread runs a chunk never changes what it computes (docs/design.md §2), so results
// that are written per item or reduced per chunk in a fixed order are deterministic.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace rs {

class ThreadPool {
public:
    // threads <= 0: one per hardware thread.
    explicit ThreadPool(int threads);
    ~ThreadPool();
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    int size() const { return int(workers_.size()) + 1; }  // the calling thread works too

    using ChunkFn = std::function<void(int64_t begin, int64_t end, int thread)>;
    // Runs fn over [0, n) in chunks of `chunk`; rethrows the first exception a chunk threw.
    // A requested stop (core/stop.h) ends it between chunks with Error(Interrupted).
    void parallelFor(int64_t n, int64_t chunk, const ChunkFn& fn);

    static int hardwareThreads();

private:
    void workerLoop(int thread);
    void runChunks(int thread);

    std::vector<std::thread> workers_;
    std::mutex mutex_;
    std::condition_variable wake_, done_;
    uint64_t generation_ = 0;
    bool stop_ = false;
    int busy_ = 0;

    // The current job.
    const ChunkFn* fn_ = nullptr;
    int64_t n_ = 0, chunk_ = 1;
    std::atomic<int64_t> next_{0};
    std::exception_ptr error_;
    std::atomic<bool> failed_{false};
};

}  // namespace rs
