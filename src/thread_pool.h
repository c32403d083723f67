// A small pool of persistent worker threads for data-parallel loops. parallel_for splits
// [0, n) into size() contiguous chunks, one per thread (the caller runs the first), and
// returns when all are done. Which chunk a thread gets never depends on scheduling, and the
// engine only uses it where each index writes its own slot, so results do not depend on the
// number of threads.
#pragma once
#include <condition_variable>
#include <type_traits>
#include <mutex>
#include <thread>
#include <vector>

namespace demlab {

class ThreadPool {
public:
    explicit ThreadPool(int threads) : threads_(threads < 1 ? 1 : threads) {
        for (int k = 1; k < threads_; ++k) workers_.emplace_back([this, k] { loop(k); });
    }
    ~ThreadPool() {
        {
            std::lock_guard<std::mutex> lock(mu_);
            stop_ = true;
            ++generation_;
        }
        cv_.notify_all();
        for (auto& t : workers_) t.join();
    }
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    int size() const { return threads_; }

    // fn(begin, end, chunk) for chunk = 0 .. size() - 1. The job is passed as a pointer and a
    // trampoline, not a std::function: no allocation per call (it runs every step).
    template <typename F>
    void parallel_for(size_t n, F&& fn) {
        if (threads_ == 1 || n < 256) {
            fn(size_t(0), n, 0);
            return;
        }
        {
            std::lock_guard<std::mutex> lock(mu_);
            job_ = static_cast<void*>(&fn);
            call_ = [](void* f, size_t b, size_t e, int k) { (*static_cast<std::remove_reference_t<F>*>(f))(b, e, k); };
            n_ = n;
            pending_ = threads_ - 1;
            ++generation_;
        }
        cv_.notify_all();
        fn(size_t(0), chunk_end(0), 0);
        std::unique_lock<std::mutex> lock(mu_);
        done_.wait(lock, [this] { return pending_ == 0; });
        job_ = nullptr;
    }

private:
    size_t chunk_begin(int k) const { return n_ * size_t(k) / size_t(threads_); }
    size_t chunk_end(int k) const { return n_ * size_t(k + 1) / size_t(threads_); }

    void loop(int k) {
        unsigned long seen = 0;
        while (true) {
            void* job;
            void (*call)(void*, size_t, size_t, int);
            {
                std::unique_lock<std::mutex> lock(mu_);
                cv_.wait(lock, [&] { return generation_ != seen; });
                seen = generation_;
                if (stop_) return;
                job = job_;
                call = call_;
            }
            call(job, chunk_begin(k), chunk_end(k), k);
            {
                std::lock_guard<std::mutex> lock(mu_);
                if (--pending_ == 0) done_.notify_one();
            }
        }
    }

    int threads_;
    std::vector<std::thread> workers_;
    std::mutex mu_;
    std::condition_variable cv_, done_;
    void* job_ = nullptr;
    void (*call_)(void*, size_t, size_t, int) = nullptr;
    size_t n_ = 0;
    int pending_ = 0;
    unsigned long generation_ = 0;
    bool stop_ = false;
};

}  // namespace demlab
