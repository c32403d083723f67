// integrate_kernel.h: World::integrate_discs' loop a group of discs at a time, written once over
// the lanes of dem/lanes/ and compiled for each width by its own file: four discs in AVX2
// registers (integrate_avx2.cpp, lane set lanes::Avx2) and eight in AVX-512 ones
// (integrate_avx512.cpp, lanes::Avx512). The includer defines DEMLAB_WIDE_TARGET, the target
// its functions are compiled for, before it includes this (lanes/wide_target.h).
//
// Same bits as the scalar loop at either width: each lane does its operations in its order (no
// FMA, lanes_avx2.h), the conditions become selects, and the ledger's terms are added disc by
// disc in disc order. The kinetic energy goes into four lanes, disc i into lane i % 4, as
// LedgerBlock says: a group of eight adds its first four discs, then its last four. The last
// group of a range may hold fewer discs than the width: its missing lanes repeat the last disc
// and are not stored.
#pragma once
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "dem/integrate_kernel.h"
#include "dem/lanes/lanes_avx2.h"
#include "dem/lanes/wide_target.h"

namespace demlab {
namespace integrate_wide {

// lane l reads index i0 + min(l, n - 1) (no target: the lambdas that gather call it)
[[gnu::always_inline]] static inline size_t lane(size_t i0, size_t n, size_t l) { return i0 + std::min(l, n - 1); }

// A group's loads (DiscLoad, one 64-byte record per disc) as eight registers of fields: fx,
// fy, torque, k_tran, k_rot, dissipated, wall_normal and the two counts (n_disc in the low,
// n_wall in the high 32 bits of a 64-bit lane). Transposed records, where a register per
// field gathered from the records took a load per lane and the shuffles to join them
// (callgrind: the gathers and the ledger's per-disc loop were a third of this loop's
// instructions).
template <typename W>
struct LoadLanes {
    typename W::D fx, fy, torque, k_tran, k_rot, dissipated, wall_normal;
    typename W::I counts;
};

template <typename W>
DEMLAB_WIDE LoadLanes<W> load_loads(const DiscLoad* const rows[W::kWidth]) {
    static_assert(sizeof(DiscLoad) == 64 && alignof(DiscLoad) == 64);
    static_assert(offsetof(DiscLoad, force) == 0 && offsetof(DiscLoad, torque) == 16 && offsetof(DiscLoad, k_tran) == 24 &&
                  offsetof(DiscLoad, k_rot) == 32 && offsetof(DiscLoad, dissipated) == 40 &&
                  offsetof(DiscLoad, wall_normal) == 48 && offsetof(DiscLoad, n_disc) == 56 &&
                  offsetof(DiscLoad, n_wall) == 60);
    const double* r[W::kWidth];
    for (size_t l = 0; l < W::kWidth; ++l) r[l] = reinterpret_cast<const double*>(rows[l]);
    typename W::D f[8];
    W::transpose_records(r, f);
    return {f[0], f[1], f[2], f[3], f[4], f[5], f[6], W::as_int(f[7])};
}

// local damping of a force or torque f against a velocity v (eq. 2.51), as the scalar loop:
// v > 0 ? -alpha |f| : (v < 0 ? alpha |f| : 0); a NaN velocity gives 0 there too
template <typename W, typename D>
DEMLAB_WIDE D local_damping(D v, D f, D alpha, D minus_alpha) {
    const D abs_f = abs(f);
    const D zero = W::zero();
    return select(cmp<_CMP_GT_OQ>(v, zero), minus_alpha * abs_f, select(cmp<_CMP_LT_OQ>(v, zero), alpha * abs_f, zero));
}

// lanes with n_disc > 0, and with n_wall > 0 (the counts are never negative: n_disc << 32 is
// positive iff n_disc is; n_wall 2^32 + n_disc exceeds 2^32 - 1 iff n_wall >= 1)
template <typename W>
DEMLAB_WIDE typename W::M touches_disc(typename W::I counts) {
    return greater(shift_left<32>(counts), W::zero_int());
}
template <typename W>
DEMLAB_WIDE typename W::M touches_wall(typename W::I counts) {
    return greater(counts, W::set1_int(0xffffffffLL));
}

// The critical step of a group (World::critical_step_squared_at; std::min(best, t) is
// min(t, best)) into best_sq.
template <typename W>
struct StepConsts {
    typename W::D zero, phi_sq, phi_t_sq, widen, smallest_normal, def_tran_one, def_rot_one;
    bool one_material, rotation_free;
    const int32_t* material;
    const double* default_k_tran;
    const double* default_k_rot;
};
template <typename W>
DEMLAB_WIDE void critical_step_group(const LoadLanes<W>& ld, typename W::D mass, typename W::D inertia,
                                     typename W::D radius, size_t i0, size_t n, const StepConsts<W>& k,
                                     typename W::D& best_sq) {
    using D = typename W::D;
    using M = typename W::M;
    const D zero = k.zero, phi_sq = k.phi_sq, phi_t_sq = k.phi_t_sq, widen = k.widen;
    const D smallest_normal = k.smallest_normal;
    D def_tran = k.def_tran_one, def_rot = k.def_rot_one;
    if (!k.one_material) {
        const int32_t* const m = k.material;
        const double* const default_k_tran = k.default_k_tran;
        const double* const default_k_rot = k.default_k_rot;
        def_tran = W::gather([&](size_t l) { return default_k_tran[m[lane(i0, n, l)]]; });
        def_rot = W::gather([&](size_t l) { return default_k_rot[m[lane(i0, n, l)]]; });
    }
    const D kt = select(cmp<_CMP_GT_OQ>(ld.k_tran, zero), ld.k_tran, def_tran);
    const D kr = select(cmp<_CMP_GT_OQ>(ld.k_rot, zero), ld.k_rot, def_rot);
    const D a_t = phi_t_sq * mass;
    const D a_r = phi_sq * inertia, b_r = kr * radius * radius;
    // Only the smallest quotient counts, and the divisions (two per group, 13 cycles
    // each) were where this loop's time piled up (perf). A lane's quotient a / b cannot
    // go below its best so far, T, when a >= T b; and fl(a / b) >= T then, rounding
    // being monotonic. P = fl(T b) is within 2^-53 of T b when it is a normal number,
    // so a >= fl(P (1 + 2^-51)) proves a >= T b. A group none of whose lanes can win
    // skips the divisions; the others divide as always, so the bits are the same.
    // (A NaN or infinite T or quotient fails the test and is divided.)
    const D p_t = best_sq * kt;
    M cannot_win = cmp<_CMP_GE_OQ>(a_t, p_t * widen) & cmp<_CMP_GE_OQ>(p_t, smallest_normal);
    if (k.rotation_free) {
        const D p_r = best_sq * b_r;
        cannot_win = cannot_win & (cmp<_CMP_GE_OQ>(a_r, p_r * widen) & cmp<_CMP_GE_OQ>(p_r, smallest_normal));
    }
    if (!all(cannot_win)) {
        D t2 = a_t / kt;
        if (k.rotation_free) {
            const D r2 = a_r / b_r;
            t2 = select(cmp<_CMP_LT_OQ>(r2, t2), r2, t2);
        }
        best_sq = min(t2, best_sq);
    }
}

// The rotation of a group (World::integrate_discs' models 2 and 3): the new spin and angle
// stored, the local damping's rotational work into diss_local, the rotational kinetic energy
// into kinetic; returns the rotation rules' dissipation.
template <typename W>
struct RotationConsts {
    typename W::D dt, zero, half, alpha, minus_alpha, g_abs, mu_br;
    bool local, rolling_literal;
    int rotation_model;
};
template <typename W>
DEMLAB_WIDE typename W::D rotate_group(const LoadLanes<W>& ld, double* omega_a, double* angle_a,
                                       const double* inv_inertia_a, const double* rr_factor_a, size_t i0, size_t n,
                                       typename W::D inv_mass, typename W::D inertia, const RotationConsts<W>& k,
                                       typename W::D& diss_local, typename W::D& kinetic) {
    using D = typename W::D;
    using M = typename W::M;
    const D dt = k.dt, zero = k.zero, half = k.half, alpha = k.alpha, minus_alpha = k.minus_alpha;
    const D tq = ld.torque;
    const D w_old = W::load_n(omega_a + i0, n);
    D tq_damped = tq, td = zero;
    if (k.local) {
        td = local_damping<W>(w_old, tq, alpha, minus_alpha);
        tq_damped = tq + td;
    }
    const D w_free = w_old + tq_damped * W::load_n(inv_inertia_a + i0, n) * dt;
    if (k.local) diss_local = diss_local - half * td * (w_old + w_free) * dt;
    D w = w_free;
    // Model 2/3: rolling resistance for a disc touching a wall (reduce_towards_zero)
    const D rr = W::load_n(rr_factor_a + i0, n);
    const M rolling = touches_wall<W>(ld.counts) & cmp<_CMP_GT_OQ>(rr, zero);
    if (any(rolling)) {
        const D g_eff = k.rolling_literal ? k.g_abs : ld.wall_normal * inv_mass;
        const D delta = g_eff * rr * dt;
        const D reduced = select(cmp<_CMP_GT_OQ>(w, delta), w - delta, select(cmp<_CMP_LT_OQ>(w, -delta), w + delta, zero));
        w = select(rolling, reduced, w);
    }
    // Model 3: rotational damping of a disc touching another (per disc)
    if (k.rotation_model == 3) w = select(touches_disc<W>(ld.counts), w * k.mu_br, w);
    const D taken = half * inertia * (w_free * w_free - w * w);
    const D torque_work = half * tq * dt * (w_free - w);
    const D diss_rot = zero + (taken - torque_work);
    kinetic = kinetic + half * inertia * (w * w);
    W::store_n(omega_a + i0, n, w);
    W::store_n(angle_a + i0, n, W::load_n(angle_a + i0, n) + w * dt);
    return diss_rot;
}

// The ledger's sums: the contacts' dissipation and the rotation rules' terms, disc by disc in
// order as the scalar loops add them (two chains of additions that run beside the vector work;
// as passes of their own after the loop they cost 3 % of DB-9k's step). The kinetic energy per
// lane (disc i in lane i % 4: the groups start at multiples of 4), added up at the block's
// end: no chain of additions for it (the ledger's chains were a sixth of this loop's time).
// The block being summed and the disc after its last, as a running count (`% block_size` with
// a run-time divisor was four 64-bit divisions per group).
struct LedgerSums {
    double sum_contacts, sum_rotation, sum_local;
    lanes::D4 kinetic_lanes;
    size_t block, block_end;
};
template <typename W>
DEMLAB_WIDE void ledger_group(const LoadLanes<W>& ld, typename W::D diss_rot, typename W::D diss_local,
                              typename W::D kinetic, size_t i0, size_t n, bool local, size_t end, size_t block_size,
                              LedgerBlock* blocks, LedgerSums& L) {
    using D = typename W::D;
    constexpr size_t N = W::kWidth;
    alignas(64) double diss_terms[N], rot_terms[N], local_terms[N];
    W::store(diss_terms, ld.dissipated);
    W::store(rot_terms, diss_rot);
    W::store(local_terms, diss_local);
    if (n == N && i0 + N < L.block_end) {
        for (size_t k = 0; k < N / 4; ++k) L.kinetic_lanes = L.kinetic_lanes + W::four(kinetic, k);
        for (size_t l = 0; l < N; ++l) {
            L.sum_contacts += diss_terms[l];
            L.sum_rotation += rot_terms[l];
        }
        if (local)
            for (size_t l = 0; l < N; ++l) L.sum_local += local_terms[l];
    } else {
        // four discs at a time, as the blocks may end after any fourth disc (the lanes beyond
        // n add +0, which leaves the sums of +0 or more unchanged)
        const D kinetic_valid = keep(W::first(n), kinetic);
        for (size_t l0 = 0; l0 < n; l0 += 4) {
            L.kinetic_lanes = L.kinetic_lanes + W::four(kinetic_valid, l0 / 4);
            for (size_t l = l0; l < std::min(n, l0 + 4); ++l) {
                L.sum_contacts += diss_terms[l];
                L.sum_rotation += rot_terms[l];
                L.sum_local += local_terms[l];
                if (i0 + l + 1 == L.block_end) {
                    LedgerBlock& b = blocks[L.block];
                    b.contacts = L.sum_contacts;
                    b.local = L.sum_local;
                    b.rotation = L.sum_rotation;
                    alignas(32) double k[4];
                    lanes::Avx2::store(k, L.kinetic_lanes);
                    b.kinetic = (k[0] + k[1]) + (k[2] + k[3]);
                    L.kinetic_lanes = lanes::Avx2::zero();
                    L.sum_contacts = L.sum_rotation = L.sum_local = 0.0;
                    ++L.block;
                    L.block_end = std::min(L.block_end + block_size, end);
                }
            }
        }
    }
}

template <typename W>
DEMLAB_WIDE IntegrateOut integrate(const IntegrateArrays& a, const IntegrateParams& p, size_t begin, size_t end,
                                   LedgerBlock* blocks, size_t block_size) {
    using D = typename W::D;
    using M = typename W::M;
    using I = typename W::I;
    constexpr size_t N = W::kWidth;
    const D dt = W::set1(p.dt);
    const D gx = W::set1(p.g.x()), gy = W::set1(p.g.y());
    const D zero = W::zero(), half = W::set1(0.5);
    const D lo_x = W::set1(p.domain_lo.x()), lo_y = W::set1(p.domain_lo.y());
    const D hi_x = W::set1(p.domain_hi.x()), hi_y = W::set1(p.domain_hi.y());
    const D phi_sq = W::set1(p.phi_sq), phi_t_sq = W::set1(p.phi_t_sq);
    const D g_abs = W::set1(p.g_abs), mu_br = W::set1(p.mu_br);
    // one material: its stiffnesses for a disc without contacts, the same in every lane
    const bool one_material = a.n_materials == 1;
    const D def_tran_one = W::set1(a.default_k_tran[0]), def_rot_one = W::set1(a.default_k_rot[0]);
    D best_sq = W::set1(p.auto_dt ? p.best_sq_start : INFINITY);
    const D widen = W::set1(1.0 + 0x1p-51), smallest_normal = W::set1(0x1p-1022);
    D speed_l1 = zero, extent_l1 = zero;  // (a NaN is caught by the domain test)
    IntegrateOut out{INFINITY, SIZE_MAX, false, 0.0, 0.0, 0};
    // local damping (eq. 2.51), as the scalar loop: F_d = -alpha |F| sign(v) per degree of freedom
    const bool local = p.alpha > 0.0;
    const D alpha = W::set1(p.alpha), minus_alpha = W::set1(-p.alpha);
    // the touching disc-disc contacts, n_disc summed as 64-bit integers (any order gives the
    // same count)
    I touching = W::zero_int();
    LedgerSums ledger{0.0, 0.0, 0.0, lanes::Avx2::zero(), begin / block_size,
                      std::min((begin / block_size + 1) * block_size, end)};

    // the parameters and arrays as locals: the stores below may alias anything reached
    // through a reference, and GCC would reload them every group
    const bool auto_dt = p.auto_dt;
    const int rotation_model = p.rotation_model;
    const DiscLoad* const loads = a.load;
    const double *const mass_a = a.mass, *const inv_mass_a = a.inv_mass, *const inertia_a = a.inertia;
    const double *const inv_inertia_a = a.inv_inertia, *const radius_a = a.radius, *const rr_factor_a = a.rr_factor;
    double *const vel_a = a.vel->data(), *const pos_a = a.pos->data();
    double *const omega_a = a.omega, *const angle_a = a.angle;
    const double *const fat_lo_a = a.fat_lo->data(), *const fat_hi_a = a.fat_hi->data();
    const StepConsts<W> step_consts{zero,          phi_sq,          phi_t_sq,          widen,
                                    smallest_normal, def_tran_one,  def_rot_one,       one_material,
                                    p.rotation_free, a.material,    a.default_k_tran,  a.default_k_rot};
    const RotationConsts<W> rotation_consts{dt,    zero,  half,  alpha, minus_alpha, g_abs, mu_br,
                                            local, p.rolling_literal, rotation_model};

    // One group of discs from i0 (n < N only for the range's last group: its missing lanes
    // repeat its last disc and are not stored). Full groups and the last one are two
    // instances, so the full ones carry no test of n.
    auto group = [&](size_t i0, size_t n) DEMLAB_WIDE_LAMBDA {
        const DiscLoad* rows[N];
        for (size_t l = 0; l < N; ++l) rows[l] = loads + lane(i0, n, l);
        const LoadLanes<W> ld = load_loads<W>(rows);
        const D mass = W::load_n(mass_a + i0, n), inv_mass = W::load_n(inv_mass_a + i0, n);
        const D inertia = W::load_n(inertia_a + i0, n), radius = W::load_n(radius_a + i0, n);

        if (auto_dt) critical_step_group<W>(ld, mass, inertia, radius, i0, n, step_consts, best_sq);

        // translation: v += (F + m g) / m dt, x += v dt
        D fx = ld.fx + mass * gx;
        D fy = ld.fy + mass * gy;
        D vx, vy, px, py;
        W::load_xy_run(vel_a + 2 * i0, n, vx, vy);
        W::load_xy_run(pos_a + 2 * i0, n, px, py);
        const D vx_old = vx, vy_old = vy;
        D fdx = zero, fdy = zero;
        if (local) {
            fdx = local_damping<W>(vx_old, fx, alpha, minus_alpha);
            fdy = local_damping<W>(vy_old, fy, alpha, minus_alpha);
            fx = fx + fdx;
            fy = fy + fdy;
        }
        const D s = inv_mass * dt;
        vx = vx + fx * s;
        vy = vy + fy * s;
        // the local damping's centred work, as the scalar loop: 0.0 - 0.5 fd.(v_old + v_new) dt,
        // less the rotation's below
        D diss_local = zero;
        if (local) {
            const D dot = fdx * (vx_old + vx) + fdy * (vy_old + vy);
            diss_local = zero - half * dot * dt;
        }
        px = px + vx * dt;
        py = py + vy * dt;
        W::store_xy_run(vel_a + 2 * i0, n, vx, vy);
        W::store_xy_run(pos_a + 2 * i0, n, px, py);
        speed_l1 = max(speed_l1, abs(vx) + abs(vy));
        extent_l1 = max(extent_l1, abs(px) + abs(py));

        // the kinetic energy after the step, translation then rotation (World::integrate_discs)
        D kinetic = half * mass * (vx * vx + vy * vy);

        // rotation
        D diss_rot = zero;
        if (rotation_model != 1)
            diss_rot = rotate_group<W>(ld, omega_a, angle_a, inv_inertia_a, rr_factor_a, i0, n, inv_mass, inertia,
                                       rotation_consts, diss_local, kinetic);
        ledger_group<W>(ld, diss_rot, diss_local, kinetic, i0, n, local, end, block_size, blocks, ledger);
        // the lanes beyond n repeat the last disc: not counted
        const M valid = W::first(n);
        touching = touching + keep(valid, ld.counts & W::set1_int(0xffffffffLL));

        // outside the domain or not a number; left the fat box
        const unsigned valid_bits = (1u << n) - 1u;
        const M inside = (cmp<_CMP_GE_OQ>(px, lo_x) & cmp<_CMP_LE_OQ>(px, hi_x)) &
                         (cmp<_CMP_GE_OQ>(py, lo_y) & cmp<_CMP_LE_OQ>(py, hi_y));
        const unsigned bad = ~bits(inside) & valid_bits;
        if (bad != 0 && out.fault == SIZE_MAX) out.fault = i0 + size_t(__builtin_ctz(bad));
        if (!out.any_escaped) {
            D flo_x, flo_y, fhi_x, fhi_y;
            W::load_xy_run(fat_lo_a + 2 * i0, n, flo_x, flo_y);
            W::load_xy_run(fat_hi_a + 2 * i0, n, fhi_x, fhi_y);
            const M in_box = (cmp<_CMP_LE_OQ>(flo_x, px - radius) & cmp<_CMP_LE_OQ>(flo_y, py - radius)) &
                             (cmp<_CMP_LE_OQ>(px + radius, fhi_x) & cmp<_CMP_LE_OQ>(py + radius, fhi_y));
            out.any_escaped = (~bits(in_box) & valid_bits) != 0;
        }
    };
    size_t i0 = begin;
    for (; i0 + N <= end; i0 += N) group(i0, N);
    if (i0 < end) group(i0, end - i0);
    {
        alignas(64) double sp[N], ex[N];
        W::store(sp, speed_l1);
        W::store(ex, extent_l1);
        for (size_t l = 0; l < N; ++l) {
            out.speed_l1 = std::max(out.speed_l1, sp[l]);
            out.extent_l1 = std::max(out.extent_l1, ex[l]);
        }
        alignas(64) int64_t t[N];
        W::store_int(t, touching);
        long sum = 0;
        for (int64_t x : t) sum += long(x);
        out.touching_dd = sum;
    }
    if (p.auto_dt) {
        alignas(64) double b[N];
        W::store(b, best_sq);
        for (double x : b) out.best_sq = std::min(out.best_sq, x);
    }
    return out;
}

}  // namespace integrate_wide
}  // namespace demlab

#endif
