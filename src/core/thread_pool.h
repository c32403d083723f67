// A small pool of persistent worker threads for data-parallel loops. parallel_for splits
// [0, n) into size() contiguous chunks, one per thread (the caller runs the first), and
// returns when all are done. Which chunk a thread gets never depends on scheduling, and the
// engine only uses it where each index writes its own slot, so results do not depend on the
// number of threads.
//
// A step calls parallel_for four times, a few hundred microseconds apart. Waking a sleeping
// thread through a condition variable costs tens of microseconds (futex, scheduler): perf
// put 8.5 % of a 2-thread DB-9k run there. So both sides spin first: a worker polls for the
// next job for up to kSpin before it sleeps, and the caller polls for the workers' end. The
// condition variables remain for the long gaps (output, the serial parts of a run).
#pragma once
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define DEMLAB_CPU_RELAX() _mm_pause()
#else
#define DEMLAB_CPU_RELAX() ((void)0)
#endif

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
            generation_.fetch_add(1, std::memory_order_release);
        }
        cv_.notify_all();
        for (auto& t : workers_) t.join();
    }
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    int size() const { return threads_; }

    // Below this many items a loop runs on the caller alone: a few microseconds of work do not
    // pay for a hand-over, and on a busy machine (more runnable threads than cores) every
    // hand-over waits for the scheduler. Measured on geometry A at scale 20 (364 discs), 1 s
    // of flow: 2.4 s on 1 thread, 2.9 s on 2 with the machine idle, 18.5 s on 2 with the
    // other core busy.
    static constexpr size_t kMinParallel = 4096;
    // whether a loop over n items is shared out (parallel_for's rule)
    bool shares(size_t n) const { return threads_ > 1 && n >= kMinParallel; }

    // fn(begin, end, chunk) for chunk = 0 .. size() - 1. The job is passed as a pointer and a
    // trampoline, not a std::function: no allocation per call (it runs every step).
    template <typename F>
    void parallel_for(size_t n, F&& fn) {
        if (!shares(n)) {
            fn(size_t(0), n, 0);
            return;
        }
        dispatch(n, fn);
    }

    // fn(k) for k = 0 .. size() - 1, each on its own thread (the caller runs 0), whatever the
    // size of the work: for passes that split their work themselves.
    template <typename F>
    void for_each_thread(F&& fn) {
        if (threads_ == 1) {
            fn(0);
            return;
        }
        auto one = [&fn](size_t begin, size_t, int) { fn(int(begin)); };
        dispatch(size_t(threads_), one);
    }

private:
    static constexpr std::chrono::microseconds kSpin{200};

    template <typename F>
    void dispatch(size_t n, F& fn) {
        job_ = static_cast<void*>(&fn);
        call_ = [](void* f, size_t b, size_t e, int k) { (*static_cast<F*>(f))(b, e, k); };
        n_ = n;
        pending_.store(threads_ - 1, std::memory_order_relaxed);
        {
            // under the lock: a worker between its last poll and its sleep cannot miss it
            std::lock_guard<std::mutex> lock(mu_);
            generation_.fetch_add(1, std::memory_order_release);
            if (sleeping_ > 0) cv_.notify_all();
        }
        fn(size_t(0), chunk_end(0), 0);
        if (!spin_until([&] { return pending_.load(std::memory_order_acquire) == 0; })) {
            std::unique_lock<std::mutex> lock(mu_);
            done_.wait(lock, [this] { return pending_.load(std::memory_order_acquire) == 0; });
        }
        job_ = nullptr;
    }

    // polls `ready` for up to kSpin; true if it became true. After the first few thousand
    // polls it yields between polls: on a machine with more runnable threads than cores
    // (two runs side by side, a test suite) the thread it waits for may need this core.
    template <typename Pred>
    static bool spin_until(Pred ready) {
        const auto until = std::chrono::steady_clock::now() + kSpin;
        for (unsigned k = 1;; ++k) {
            if (ready()) return true;
            if (k < 2048)
                DEMLAB_CPU_RELAX();
            else
                std::this_thread::yield();
            if ((k & 63) == 0 && std::chrono::steady_clock::now() > until) return ready();
        }
    }

    size_t chunk_begin(int k) const { return n_ * size_t(k) / size_t(threads_); }
    size_t chunk_end(int k) const { return n_ * size_t(k + 1) / size_t(threads_); }

    void loop(int k) {
        unsigned long seen = 0;
        while (true) {
            auto fresh = [&] { return generation_.load(std::memory_order_acquire) != seen; };
            if (!spin_until(fresh)) {
                std::unique_lock<std::mutex> lock(mu_);
                ++sleeping_;
                cv_.wait(lock, fresh);
                --sleeping_;
            }
            seen = generation_.load(std::memory_order_acquire);
            if (stop_) return;
            call_(job_, chunk_begin(k), chunk_end(k), k);
            if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
                std::lock_guard<std::mutex> lock(mu_);
                done_.notify_one();
            }
        }
    }

    int threads_;
    std::vector<std::thread> workers_;
    std::mutex mu_;
    std::condition_variable cv_, done_;
    // written by the caller before generation_ is bumped (release), read after (acquire)
    void* job_ = nullptr;
    void (*call_)(void*, size_t, size_t, int) = nullptr;
    size_t n_ = 0;
    std::atomic<int> pending_{0};
    std::atomic<unsigned long> generation_{0};
    int sleeping_ = 0;  // under mu_
    bool stop_ = false; // written under mu_ before the last bump
};

}  // namespace demlab
