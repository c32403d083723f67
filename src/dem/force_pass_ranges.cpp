// The force pass' ranges (World::split_force_pass and its balancing): which discs and
// contacts each thread owns in the pass (force_pass.cpp), which pairs cross between ranges,
// and how the cut follows the ranges' measured times. No bit depends on the cut.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/error.h"
#include "core/validate.h"
#include "core/thread_pool.h"
#include "dem/range_balance.h"
#include "dem/world.h"

namespace demlab {

// The force pass's ranges: one contiguous range of discs per thread, cut where the work
// (contacts owned, plus discs) is shared in the ranges' target shares (equal at first, then
// corrected from the measured times: balance_force_pass); the cross contacts and, per range,
// which of them it receives. Rebuilt with the candidate lists. How the work is cut changes no
// bit: every disc sums its terms in contact-list order in any case (compute_forces).
//
// Ranges pay off when discs near in space are near in index, so that few pairs cross (flume
// 2 %, DB-9k 1 % of the candidates on 2 threads). A world in random order (the release
// generator's, before its mass is ordered in space) has half its pairs crossing: the first
// range then waits for the second to compute them all before its first pair, and 2 threads
// took 131 s where 1 thread took 89 s for the release of geometry A. Above
// max_cross_share_ of the candidates crossing, the pass runs as one range on the calling
// thread: the same bits, at the 1-thread speed. The limit, 10 %, is where 2 ranges stopped
// beating one on DB-9k with part of its discs swapped at random (ns per particle-step,
// 1 / 2 threads: 0.7 % crossing 30 / 19-25, 5 % 31-48 / 28, 9 % 32-38 / 31-32, 16 % 36-38 /
// 39-44, 27 % 45 / 52, 42 % 34 / 65).
void World::split_force_pass() {
    const size_t n = pos_.size();
    const size_t wanted = pool_->shares(n) && one_range_left_ == 0 ? size_t(pool_->size()) : 1;
    if (range_share_.size() != wanted) range_share_.assign(wanted, 1.0 / double(wanted));
    cut_ranges(wanted);
    if (wanted > 1 && double(cross_.size()) > max_cross_share_ * double(dd_.size())) {
        ++one_range_cuts_;
        cut_ranges(1);
    }
    // A new cut of the same number of ranges keeps the balancing window: the lists are rebuilt
    // every few steps in a flow (geometry A at scale 4: every 11 steps on average), and a
    // window restarted at each of them never reached its kBalanceWindow steps, so the flume's
    // ranges were never balanced (their times 25 % apart). The shares are fractions of the work
    // model, so times measured under one cut still say how to move them under the next.
    if (range_clock_.size() != size_t(force_ranges_)) restart_balance_window();
}

void World::cut_ranges(size_t r) {
    const size_t n = pos_.size();
    force_ranges_ = int(r);
    ledger_blocks_.resize((n + kLedgerBlock - 1) / kLedgerBlock);
    // the ranges' first disc, disc-disc contact and wall contact (both lists are sorted by disc)
    disc_split_.assign(r + 1, n);
    contact_split_.assign(r + 1, dd_.size());
    wall_split_.assign(r + 1, dw_.size());
    disc_split_[0] = contact_split_[0] = wall_split_[0] = 0;
    if (r > 1) {
        // work of disc d: 1 + the contacts it owns
        const double total = double(n + dd_.size() + dw_.size());
        size_t k = 0, kw = 0, part = 1;
        double done = 0.0, target = total * range_share_[0];
        for (size_t d = 0; d < n && part < r; ++d) {
            const size_t k0 = k, kw0 = kw;
            while (k < dd_.size() && size_t(dd_[k].i) == d) ++k;
            while (kw < dw_.size() && size_t(dw_[kw].disc) == d) ++kw;
            done += double(1 + (k - k0) + (kw - kw0));
            // ranges hold whole ledger blocks, so the ledger's sums do not depend on the cut
            if (done >= target && (d + 1) % kLedgerBlock == 0) {
                disc_split_[part] = d + 1;
                contact_split_[part] = k;
                wall_split_[part] = kw;
                target += total * range_share_[part];
                ++part;
            }
        }
    }
    cross_.clear();
    cross_in_.clear();
    cross_start_.assign(r + 1, 0);
    cross_in_start_.assign(r + 1, 0);
    if (r > 1) {
        auto range_of = [&](int32_t d) {
            return size_t(std::upper_bound(disc_split_.begin(), disc_split_.end(), size_t(d)) - disc_split_.begin()) - 1;
        };
        for (size_t t = 0; t < r; ++t) {
            cross_start_[t] = cross_.size();
            for (size_t k = contact_split_[t]; k < contact_split_[t + 1]; ++k)
                if (size_t(dd_[k].j) >= disc_split_[t + 1]) {
                    cross_.push_back(int32_t(k));
                    ++cross_in_start_[range_of(dd_[k].j) + 1];
                }
        }
        cross_start_[r] = cross_.size();
        for (size_t t = 0; t < r; ++t) cross_in_start_[t + 1] += cross_in_start_[t];
        cross_in_.resize(cross_.size());
        std::vector<int32_t> fill(cross_in_start_.begin(), cross_in_start_.end() - 1);
        for (size_t m = 0; m < cross_.size(); ++m)
            cross_in_[size_t(fill[range_of(dd_[size_t(cross_[m])].j)]++)] = int32_t(m);
    }
    cross_out_.resize(cross_.size());
    cross_todo_.assign(cross_.size(), 0);
    cross_copies_stale_ = true;
    if (cross_done_size_ < r) {
        cross_done_ = std::make_unique<CrossDone[]>(r);  // a new array: no pass is marked done
        centre_packed_ = std::make_unique<CrossDone[]>(r);
        centre_shifted_ = std::make_unique<CrossDone[]>(r);
        cross_done_size_ = r;
    }

    // the range pass' blocks (FuseBlock) and how far ahead each one's pairs reach
    fuse_blocks_.clear();
    fuse_start_.assign(r + 1, 0);
    cross_in_reach_.assign(r, 0);
    for (size_t t = 0; t < r; ++t) {
        const size_t d0 = disc_split_[t], d1 = disc_split_[t + 1];
        size_t reach = d0;
        for (int32_t e = cross_in_start_[t]; e < cross_in_start_[t + 1]; ++e)
            reach = std::max(reach, size_t(dd_[size_t(cross_[size_t(cross_in_[size_t(e)])])].j) + 1);
        cross_in_reach_[t] = std::min(reach, d1);
        fuse_start_[t] = fuse_blocks_.size();
        size_t k = contact_split_[t], kw = wall_split_[t];
        for (size_t b0 = d0; b0 < d1;) {
            const size_t b1 = std::min(b0 + kFuseBlock, d1);
            size_t far = b1;
            for (; k < contact_split_[t + 1] && size_t(dd_[k].i) < b1; ++k) far = std::max(far, size_t(dd_[k].j) + 1);
            while (kw < wall_split_[t + 1] && size_t(dw_[kw].disc) < b1) ++kw;
            fuse_blocks_.push_back({b1, k, kw, std::min(far, d1)});  // a cross pair's j is another range's
            b0 = b1;
        }
    }
    fuse_start_[r] = fuse_blocks_.size();
}

// The ranges' work model (one unit per disc and per owned contact) misses what a unit costs:
// a touching pair costs more than a candidate that does not touch, a wall contact more than
// either, and the two cores need not run at the same speed. So every kBalanceWindow steps the
// ranges' times are compared, and when they differ by more than kBalanceTolerance the shares
// move halfway towards the measured speeds (rebalance_shares) and the pass is cut again. The
// cut changes no bit. Measured on DB-9k, 2 threads: the shares settle near 0.48/0.52.
void World::balance_force_pass() {
    if (one_range_left_ > 0) {
        ++one_range_steps_;
        if (--one_range_left_ == 0) split_force_pass();  // try the pool again
        return;
    }
    const size_t r = range_clock_.size();
    if (r < 2 || ++balance_steps_ < kBalanceWindow) return;
    double busy = 0.0;
    for (const RangeClock& c : range_clock_) busy += c.seconds;
    if (busy_fallback_ && busy_watch_.window(busy, window_pass_seconds_, r)) {
        ++busy_fallbacks_;
        run_as_one_range_for(kOneRangeSteps);
        return;
    }
    const auto seconds = [this](size_t t) { return range_clock_[t].seconds; };
    if (rebalance_shares(range_share_.data(), seconds, r, kBalanceTolerance)) {
        ++rebalances_;
        split_force_pass();
        restart_balance_window();
    } else {
        restart_balance_window();
    }
}

void World::restart_balance_window() {
    range_clock_.assign(size_t(force_ranges_), RangeClock{});
    balance_steps_ = 0;
    window_pass_seconds_ = 0.0;
}

double World::force_pass_busy_share() const {
    // a shared pass has one range per thread of the pool
    return shared_pass_seconds_ > 0.0 ? shared_pass_busy_seconds_ / (shared_pass_seconds_ * double(pool_->size())) : 1.0;
}

void World::run_as_one_range_for(long steps) {
    if (steps < 0) throw InputError("force pass: one range for " + std::to_string(steps) + " steps: must be >= 0");
    if (!finalized_) finalize();
    one_range_left_ = steps;
    split_force_pass();
}

void World::cut_force_pass(const std::vector<double>& shares) {
    if (!finalized_) finalize();
    const size_t r = size_t(pool_->shares(pos_.size()) ? pool_->size() : 1);
    double sum = 0.0;
    bool each_valid = true;
    for (double x : shares) {
        each_valid = each_valid && std::isfinite(x) && x >= 0.0;
        sum += x;
    }
    if (shares.size() != r || !each_valid || !(std::abs(sum - 1.0) < 1e-9))
        throw InputError("force-pass shares: " + std::to_string(r) +
                         " finite shares >= 0 summing to 1 expected (one per range)");
    range_share_ = shares;
    split_force_pass();
    restart_balance_window();  // times measured under other shares
}

void World::set_cross_share_limit(double share) {
    if (!(share >= 0.0 && share <= 1.0))
        throw InputError("force-pass cross share limit: " + format_number(share) + " is not in [0, 1]");
    max_cross_share_ = share;
    if (finalized_) split_force_pass();
}

}  // namespace demlab
