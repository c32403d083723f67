// integrate_kernel.h: World::integrate_discs' loop four discs at a time. Same bits as the
// scalar loop: each lane does its operations in its order (no FMA: the functions ask for
// "avx2" only), the conditions become blends, and the ledger's terms go back to the caller to
// be added in disc order. The last group of a range may hold fewer than four discs: its
// missing lanes repeat the last disc and are not stored.
#include <immintrin.h>

#include <algorithm>
#include <cmath>

#include "dem/integrate_kernel.h"

namespace demlab {

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define DEMLAB_AVX2 [[gnu::target("avx2"), gnu::always_inline]] static inline
#define DEMLAB_AVX2_LAMBDA __attribute__((target("avx2"), always_inline))

namespace {

// lane l reads index i0 + min(l, n - 1)
DEMLAB_AVX2 size_t lane(size_t i0, size_t n, size_t l) { return i0 + std::min(l, n - 1); }

DEMLAB_AVX2 __m256d load_lanes(const double* a, size_t i0, size_t n) {
    if (n == 4) return _mm256_loadu_pd(a + i0);
    return _mm256_set_pd(a[lane(i0, n, 3)], a[lane(i0, n, 2)], a[lane(i0, n, 1)], a[i0]);
}

DEMLAB_AVX2 void store_lanes(double* a, size_t i0, size_t n, __m256d v) {
    if (n == 4) {
        _mm256_storeu_pd(a + i0, v);
        return;
    }
    alignas(32) double t[4];
    _mm256_store_pd(t, v);
    for (size_t l = 0; l < n; ++l) a[i0 + l] = t[l];
}

// four Vec2 as an x and a y register
DEMLAB_AVX2 void load_xy(const Vec2* a, size_t i0, size_t n, __m256d& x, __m256d& y) {
    if (n == 4) {
        const __m256d a01 = _mm256_loadu_pd(a[i0].data()), a23 = _mm256_loadu_pd(a[i0 + 2].data());
        x = _mm256_permute4x64_pd(_mm256_unpacklo_pd(a01, a23), 0xD8);  // x0 x2 x1 x3 -> x0 x1 x2 x3
        y = _mm256_permute4x64_pd(_mm256_unpackhi_pd(a01, a23), 0xD8);
        return;
    }
    const Vec2 &a0 = a[i0], &a1 = a[lane(i0, n, 1)], &a2 = a[lane(i0, n, 2)], &a3 = a[lane(i0, n, 3)];
    x = _mm256_set_pd(a3.x(), a2.x(), a1.x(), a0.x());
    y = _mm256_set_pd(a3.y(), a2.y(), a1.y(), a0.y());
}

DEMLAB_AVX2 void store_xy(Vec2* a, size_t i0, size_t n, __m256d x, __m256d y) {
    const __m256d t02 = _mm256_unpacklo_pd(x, y), t13 = _mm256_unpackhi_pd(x, y);  // x0 y0 x2 y2, x1 y1 x3 y3
    const __m256d a01 = _mm256_permute2f128_pd(t02, t13, 0x20), a23 = _mm256_permute2f128_pd(t02, t13, 0x31);
    if (n == 4) {
        _mm256_storeu_pd(a[i0].data(), a01);
        _mm256_storeu_pd(a[i0 + 2].data(), a23);
        return;
    }
    alignas(32) double t[8];
    _mm256_store_pd(t, a01);
    _mm256_store_pd(t + 4, a23);
    for (size_t l = 0; l < n; ++l) a[i0 + l] = Vec2(t[2 * l], t[2 * l + 1]);
}

// c ? a : b, lane by lane
DEMLAB_AVX2 __m256d blend(__m256d c, __m256d a, __m256d b) { return _mm256_blendv_pd(b, a, c); }

DEMLAB_AVX2 __m256d neg(__m256d a) { return _mm256_xor_pd(a, _mm256_set1_pd(-0.0)); }

// Four discs' loads (DiscLoad, one 64-byte record each) as eight registers of fields, by
// two 4x4 transposes: fx, fy, torque, k_tran, then k_rot, dissipated, wall_normal and the
// two counts (n_disc in the low, n_wall in the high 32 bits of a 64-bit lane). Eight
// loads and sixteen shuffles, where a register per field gathered from four records took
// four loads and three shuffles each (callgrind: the gathers and the ledger's per-disc loop
// were a third of this loop's instructions). rows[l] is lane l's disc.
struct LoadLanes {
    __m256d fx, fy, torque, k_tran, k_rot, dissipated, wall_normal;
    __m256i counts;
};

DEMLAB_AVX2 void transpose4(__m256d r0, __m256d r1, __m256d r2, __m256d r3, __m256d& f0, __m256d& f1, __m256d& f2,
                            __m256d& f3) {
    const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);  // r0[0] r1[0] r0[2] r1[2], ...
    const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
    f0 = _mm256_permute2f128_pd(t0, t2, 0x20);
    f1 = _mm256_permute2f128_pd(t1, t3, 0x20);
    f2 = _mm256_permute2f128_pd(t0, t2, 0x31);
    f3 = _mm256_permute2f128_pd(t1, t3, 0x31);
}

DEMLAB_AVX2 LoadLanes load_loads(const DiscLoad* const rows[4]) {
    static_assert(sizeof(DiscLoad) == 64 && alignof(DiscLoad) == 64);
    static_assert(offsetof(DiscLoad, force) == 0 && offsetof(DiscLoad, torque) == 16 && offsetof(DiscLoad, k_tran) == 24 &&
                  offsetof(DiscLoad, k_rot) == 32 && offsetof(DiscLoad, dissipated) == 40 &&
                  offsetof(DiscLoad, wall_normal) == 48 && offsetof(DiscLoad, n_disc) == 56 &&
                  offsetof(DiscLoad, n_wall) == 60);
    LoadLanes o;
    const double* r[4];
    for (int l = 0; l < 4; ++l) r[l] = reinterpret_cast<const double*>(rows[l]);
    transpose4(_mm256_load_pd(r[0]), _mm256_load_pd(r[1]), _mm256_load_pd(r[2]), _mm256_load_pd(r[3]), o.fx, o.fy,
               o.torque, o.k_tran);
    __m256d counts;
    transpose4(_mm256_load_pd(r[0] + 4), _mm256_load_pd(r[1] + 4), _mm256_load_pd(r[2] + 4), _mm256_load_pd(r[3] + 4),
               o.k_rot, o.dissipated, o.wall_normal, counts);
    o.counts = _mm256_castpd_si256(counts);
    return o;
}

// local damping of a force or torque f against a velocity v (eq. 2.51), as the scalar loop:
// v > 0 ? -alpha |f| : (v < 0 ? alpha |f| : 0); a NaN velocity gives 0 there too
DEMLAB_AVX2 __m256d local_damping(__m256d v, __m256d f, __m256d alpha, __m256d minus_alpha) {
    const __m256d abs_f = _mm256_andnot_pd(_mm256_set1_pd(-0.0), f);
    const __m256d zero = _mm256_setzero_pd();
    return blend(_mm256_cmp_pd(v, zero, _CMP_GT_OQ), _mm256_mul_pd(minus_alpha, abs_f),
                 blend(_mm256_cmp_pd(v, zero, _CMP_LT_OQ), _mm256_mul_pd(alpha, abs_f), zero));
}

// lanes with n_disc > 0, and with n_wall > 0, as masks (the counts are never negative:
// n_disc << 32 is positive iff n_disc is; n_wall 2^32 + n_disc exceeds 2^32 - 1 iff n_wall >= 1)
DEMLAB_AVX2 __m256d touches_disc(__m256i counts) {
    return _mm256_castsi256_pd(_mm256_cmpgt_epi64(_mm256_slli_epi64(counts, 32), _mm256_setzero_si256()));
}
DEMLAB_AVX2 __m256d touches_wall(__m256i counts) {
    return _mm256_castsi256_pd(_mm256_cmpgt_epi64(counts, _mm256_set1_epi64x(0xffffffffLL)));
}

// lane l of a, l = 0..3
DEMLAB_AVX2 double lane_of(__m256d a, int l) {
    const __m128d h = l < 2 ? _mm256_castpd256_pd128(a) : _mm256_extractf128_pd(a, 1);
    return (l & 1) ? _mm_cvtsd_f64(_mm_unpackhi_pd(h, h)) : _mm_cvtsd_f64(h);
}

// The critical step of a group (World::critical_step_squared_at; std::min(best, t) is
// min_pd(t, best)) into best_sq.
struct StepConsts {
    __m256d zero, phi_sq, phi_t_sq, widen, smallest_normal, def_tran_one, def_rot_one;
    bool one_material, rotation_free;
    const int32_t* material;
    const double* default_k_tran;
    const double* default_k_rot;
};
DEMLAB_AVX2 void critical_step_group(const LoadLanes& ld, __m256d mass, __m256d inertia, __m256d radius, size_t i0,
                                     size_t n, const StepConsts& k, __m256d& best_sq) {
    const __m256d zero = k.zero, phi_sq = k.phi_sq, phi_t_sq = k.phi_t_sq, widen = k.widen;
    const __m256d smallest_normal = k.smallest_normal, def_tran_one = k.def_tran_one, def_rot_one = k.def_rot_one;
    const bool one_material = k.one_material, rotation_free = k.rotation_free;
    const int32_t* const material = k.material;
    const double* const default_k_tran = k.default_k_tran;
    const double* const default_k_rot = k.default_k_rot;
    __m256d def_tran = def_tran_one, def_rot = def_rot_one;
    if (!one_material) {
        const int32_t* m = material;
        def_tran = _mm256_set_pd(default_k_tran[m[lane(i0, n, 3)]], default_k_tran[m[lane(i0, n, 2)]],
                                 default_k_tran[m[lane(i0, n, 1)]], default_k_tran[m[i0]]);
        def_rot = _mm256_set_pd(default_k_rot[m[lane(i0, n, 3)]], default_k_rot[m[lane(i0, n, 2)]],
                                default_k_rot[m[lane(i0, n, 1)]], default_k_rot[m[i0]]);
    }
    const __m256d kt = blend(_mm256_cmp_pd(ld.k_tran, zero, _CMP_GT_OQ), ld.k_tran, def_tran);
    const __m256d kr = blend(_mm256_cmp_pd(ld.k_rot, zero, _CMP_GT_OQ), ld.k_rot, def_rot);
    const __m256d a_t = _mm256_mul_pd(phi_t_sq, mass);
    const __m256d a_r = _mm256_mul_pd(phi_sq, inertia), b_r = _mm256_mul_pd(_mm256_mul_pd(kr, radius), radius);
    // Only the smallest quotient counts, and the divisions (two per group, 13 cycles
    // each) were where this loop's time piled up (perf). A lane's quotient a / b cannot
    // go below its best so far, T, when a >= T b; and fl(a / b) >= T then, rounding
    // being monotonic. P = fl(T b) is within 2^-53 of T b when it is a normal number,
    // so a >= fl(P (1 + 2^-51)) proves a >= T b. A group none of whose lanes can win
    // skips the divisions; the others divide as always, so the bits are the same.
    // (A NaN or infinite T or quotient fails the test and is divided.)
    const __m256d p_t = _mm256_mul_pd(best_sq, kt);
    __m256d cannot_win = _mm256_and_pd(_mm256_cmp_pd(a_t, _mm256_mul_pd(p_t, widen), _CMP_GE_OQ),
                                       _mm256_cmp_pd(p_t, smallest_normal, _CMP_GE_OQ));
    if (rotation_free) {
        const __m256d p_r = _mm256_mul_pd(best_sq, b_r);
        cannot_win = _mm256_and_pd(cannot_win, _mm256_and_pd(_mm256_cmp_pd(a_r, _mm256_mul_pd(p_r, widen), _CMP_GE_OQ),
                                                             _mm256_cmp_pd(p_r, smallest_normal, _CMP_GE_OQ)));
    }
    if (_mm256_movemask_pd(cannot_win) != 15) {
        __m256d t2 = _mm256_div_pd(a_t, kt);
        if (rotation_free) {
            const __m256d r2 = _mm256_div_pd(a_r, b_r);
            t2 = blend(_mm256_cmp_pd(r2, t2, _CMP_LT_OQ), r2, t2);
        }
        best_sq = _mm256_min_pd(t2, best_sq);
    }
}

// The rotation of a group (World::integrate_discs' models 2 and 3): the new spin and angle
// stored, the local damping's rotational work into diss_local, the rotational kinetic energy
// into kinetic; returns the rotation rules' dissipation.
struct RotationConsts {
    __m256d dt, zero, half, alpha, minus_alpha, g_abs, mu_br;
    bool local, rolling_literal;
    int rotation_model;
};
DEMLAB_AVX2 __m256d rotate_group(const LoadLanes& ld, double* omega_a, double* angle_a, const double* inv_inertia_a,
                                 const double* rr_factor_a, size_t i0, size_t n, __m256d inv_mass, __m256d inertia,
                                 const RotationConsts& k, __m256d& diss_local, __m256d& kinetic) {
    const __m256d dt = k.dt, zero = k.zero, half = k.half, alpha = k.alpha, minus_alpha = k.minus_alpha;
    const __m256d g_abs = k.g_abs, mu_br = k.mu_br;
    const bool local = k.local, rolling_literal = k.rolling_literal;
    const int rotation_model = k.rotation_model;
    __m256d diss_rot = zero;
    const __m256d tq = ld.torque;
    const __m256d w_old = load_lanes(omega_a, i0, n);
    __m256d tq_damped = tq, td = zero;
    if (local) {
        td = local_damping(w_old, tq, alpha, minus_alpha);
        tq_damped = _mm256_add_pd(tq, td);
    }
    const __m256d w_free =
        _mm256_add_pd(w_old, _mm256_mul_pd(_mm256_mul_pd(tq_damped, load_lanes(inv_inertia_a, i0, n)), dt));
    if (local)
        diss_local = _mm256_sub_pd(diss_local, _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(half, td), _mm256_add_pd(w_old, w_free)), dt));
    __m256d w = w_free;
    // Model 2/3: rolling resistance for a disc touching a wall (reduce_towards_zero)
    const __m256d rr = load_lanes(rr_factor_a, i0, n);
    const __m256d rolling = _mm256_and_pd(touches_wall(ld.counts), _mm256_cmp_pd(rr, zero, _CMP_GT_OQ));
    if (_mm256_movemask_pd(rolling) != 0) {
        const __m256d g_eff = rolling_literal ? g_abs : _mm256_mul_pd(ld.wall_normal, inv_mass);
        const __m256d delta = _mm256_mul_pd(_mm256_mul_pd(g_eff, rr), dt);
        const __m256d reduced =
            blend(_mm256_cmp_pd(w, delta, _CMP_GT_OQ), _mm256_sub_pd(w, delta),
                  blend(_mm256_cmp_pd(w, neg(delta), _CMP_LT_OQ), _mm256_add_pd(w, delta), zero));
        w = blend(rolling, reduced, w);
    }
    // Model 3: rotational damping of a disc touching another (per disc)
    if (rotation_model == 3) w = blend(touches_disc(ld.counts), _mm256_mul_pd(w, mu_br), w);
    const __m256d taken = _mm256_mul_pd(_mm256_mul_pd(half, inertia),
                                        _mm256_sub_pd(_mm256_mul_pd(w_free, w_free), _mm256_mul_pd(w, w)));
    const __m256d torque_work = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(half, tq), dt), _mm256_sub_pd(w_free, w));
    diss_rot = _mm256_add_pd(zero, _mm256_sub_pd(taken, torque_work));
    kinetic = _mm256_add_pd(kinetic, _mm256_mul_pd(_mm256_mul_pd(half, inertia), _mm256_mul_pd(w, w)));
    store_lanes(omega_a, i0, n, w);
    store_lanes(angle_a, i0, n, _mm256_add_pd(load_lanes(angle_a, i0, n), _mm256_mul_pd(w, dt)));
    return diss_rot;
}

// The ledger's terms of a group: the contacts' dissipation and the rotation rules' terms,
// added disc by disc; a block's sums are written when its last disc is added.
struct LedgerSums {
    double sum_contacts, sum_rotation, sum_local;
    __m256d kinetic_lanes;
    size_t block, block_end;
};
DEMLAB_AVX2 void ledger_group(const LoadLanes& ld, __m256d diss_rot, __m256d diss_local, __m256d kinetic, size_t i0,
                              size_t n, bool local, size_t end, size_t block_size, LedgerBlock* blocks, LedgerSums& L) {
    double& sum_contacts = L.sum_contacts;
    double& sum_rotation = L.sum_rotation;
    double& sum_local = L.sum_local;
    __m256d& kinetic_lanes = L.kinetic_lanes;
    size_t& block = L.block;
    size_t& block_end = L.block_end;
    // the ledger: the contacts' dissipation and the rotation rules' terms, added disc by
    // disc; a block's sums are written when its last disc is added
    if (n == 4 && i0 + 4 < block_end) {
        kinetic_lanes = _mm256_add_pd(kinetic_lanes, kinetic);
        sum_contacts += lane_of(ld.dissipated, 0);
        sum_rotation += lane_of(diss_rot, 0);
        sum_contacts += lane_of(ld.dissipated, 1);
        sum_rotation += lane_of(diss_rot, 1);
        sum_contacts += lane_of(ld.dissipated, 2);
        sum_rotation += lane_of(diss_rot, 2);
        sum_contacts += lane_of(ld.dissipated, 3);
        sum_rotation += lane_of(diss_rot, 3);
        if (local) {
            sum_local += lane_of(diss_local, 0);
            sum_local += lane_of(diss_local, 1);
            sum_local += lane_of(diss_local, 2);
            sum_local += lane_of(diss_local, 3);
        }
    } else {
        // (a block ends inside a group only at the range's end: the lanes after it are
        // beyond n, and add +0)
        const __m256d valid_l = _mm256_castsi256_pd(
            _mm256_cmpgt_epi64(_mm256_set1_epi64x(int64_t(n)), _mm256_setr_epi64x(0, 1, 2, 3)));
        kinetic_lanes = _mm256_add_pd(kinetic_lanes, _mm256_and_pd(valid_l, kinetic));
        alignas(32) double diss_terms[4], rot_terms[4], local_terms[4];
        _mm256_store_pd(diss_terms, ld.dissipated);
        _mm256_store_pd(rot_terms, diss_rot);
        _mm256_store_pd(local_terms, diss_local);
        for (size_t l = 0; l < n; ++l) {
            sum_contacts += diss_terms[l];
            sum_rotation += rot_terms[l];
            sum_local += local_terms[l];
            if (i0 + l + 1 == block_end) {
                LedgerBlock& b = blocks[block];
                b.contacts = sum_contacts;
                b.local = sum_local;
                b.rotation = sum_rotation;
                b.kinetic = (lane_of(kinetic_lanes, 0) + lane_of(kinetic_lanes, 1)) +
                            (lane_of(kinetic_lanes, 2) + lane_of(kinetic_lanes, 3));
                kinetic_lanes = _mm256_setzero_pd();
                sum_contacts = sum_rotation = sum_local = 0.0;
                ++block;
                block_end = std::min(block_end + block_size, end);
            }
        }
    }
}

}  // namespace

[[gnu::target("avx2")]] IntegrateOut integrate_avx2(const IntegrateArrays& a, const IntegrateParams& p, size_t begin,
                                                    size_t end, LedgerBlock* blocks, size_t block_size) {
    const __m256d dt = _mm256_set1_pd(p.dt);
    const __m256d gx = _mm256_set1_pd(p.g.x()), gy = _mm256_set1_pd(p.g.y());
    const __m256d zero = _mm256_setzero_pd(), half = _mm256_set1_pd(0.5);
    const __m256d lo_x = _mm256_set1_pd(p.domain_lo.x()), lo_y = _mm256_set1_pd(p.domain_lo.y());
    const __m256d hi_x = _mm256_set1_pd(p.domain_hi.x()), hi_y = _mm256_set1_pd(p.domain_hi.y());
    const __m256d phi_sq = _mm256_set1_pd(p.phi_sq), phi_t_sq = _mm256_set1_pd(p.phi_t_sq);
    const __m256d g_abs = _mm256_set1_pd(p.g_abs), mu_br = _mm256_set1_pd(p.mu_br);
    // one material: its stiffnesses for a disc without contacts, the same in every lane
    const bool one_material = a.n_materials == 1;
    const __m256d def_tran_one = _mm256_set1_pd(a.default_k_tran[0]), def_rot_one = _mm256_set1_pd(a.default_k_rot[0]);
    __m256d best_sq = _mm256_set1_pd(p.auto_dt ? p.best_sq_start : INFINITY);
    const __m256d widen = _mm256_set1_pd(1.0 + 0x1p-51), smallest_normal = _mm256_set1_pd(0x1p-1022);
    const __m256d sign = _mm256_set1_pd(-0.0);
    __m256d speed_l1 = zero, extent_l1 = zero;  // (a NaN is caught by the domain test)
    IntegrateOut out{INFINITY, SIZE_MAX, false, 0.0, 0.0, 0};
    // local damping (eq. 2.51), as the scalar loop: F_d = -alpha |F| sign(v) per degree of freedom
    const bool local = p.alpha > 0.0;
    const __m256d alpha = _mm256_set1_pd(p.alpha), minus_alpha = _mm256_set1_pd(-p.alpha);
    // the touching disc-disc contacts, n_disc summed as 64-bit integers (any order gives the
    // same count)
    __m256i touching = _mm256_setzero_si256();
    // The ledger's sums, disc by disc in order as the scalar loops add them (two chains of
    // additions that run beside the vector work; as passes of their own after the loop they
    // cost 3 % of DB-9k's step). The kinetic energy per lane (disc i in lane i % 4: the groups
    // start at multiples of 4), added up at the block's end: no chain of additions for it (the
    // ledger's chains were a sixth of this loop's time). The block being summed and the disc
    // after its last, as a running count (`% block_size` with a run-time divisor was four
    // 64-bit divisions per group).
    LedgerSums ledger{0.0, 0.0, 0.0, _mm256_setzero_pd(), begin / block_size,
                      std::min((begin / block_size + 1) * block_size, end)};

    // the parameters and arrays as locals: the stores below may alias anything reached
    // through a reference, and GCC would reload them every group
    const bool auto_dt = p.auto_dt, rotation_free = p.rotation_free, rolling_literal = p.rolling_literal;
    const int rotation_model = p.rotation_model;
    const DiscLoad* const loads = a.load;
    const double *const mass_a = a.mass, *const inv_mass_a = a.inv_mass, *const inertia_a = a.inertia;
    const double *const inv_inertia_a = a.inv_inertia, *const radius_a = a.radius, *const rr_factor_a = a.rr_factor;
    Vec2 *const vel_a = a.vel, *const pos_a = a.pos;
    double *const omega_a = a.omega, *const angle_a = a.angle;
    const Vec2 *const fat_lo_a = a.fat_lo, *const fat_hi_a = a.fat_hi;
    const StepConsts step_consts{zero,         phi_sq,        phi_t_sq,          widen,           smallest_normal,
                                 def_tran_one, def_rot_one,   one_material,      rotation_free,   a.material,
                                 a.default_k_tran, a.default_k_rot};
    const RotationConsts rotation_consts{dt, zero, half, alpha, minus_alpha, g_abs, mu_br, local, rolling_literal, rotation_model};

    // One group of four discs from i0 (n < 4 only for the range's last group: its missing
    // lanes repeat its last disc and are not stored). Full groups and the last one are two
    // instances, so the full ones carry no test of n.
    auto group = [&](size_t i0, size_t n) DEMLAB_AVX2_LAMBDA {
        const DiscLoad* const rows[4] = {loads + i0, loads + lane(i0, n, 1), loads + lane(i0, n, 2),
                                         loads + lane(i0, n, 3)};
        const LoadLanes ld = load_loads(rows);
        const __m256d mass = load_lanes(mass_a, i0, n), inv_mass = load_lanes(inv_mass_a, i0, n);
        const __m256d inertia = load_lanes(inertia_a, i0, n), radius = load_lanes(radius_a, i0, n);

        if (auto_dt) critical_step_group(ld, mass, inertia, radius, i0, n, step_consts, best_sq);

        // translation: v += (F + m g) / m dt, x += v dt
        __m256d fx = _mm256_add_pd(ld.fx, _mm256_mul_pd(mass, gx));
        __m256d fy = _mm256_add_pd(ld.fy, _mm256_mul_pd(mass, gy));
        __m256d vx, vy, px, py;
        load_xy(vel_a, i0, n, vx, vy);
        load_xy(pos_a, i0, n, px, py);
        const __m256d vx_old = vx, vy_old = vy;
        __m256d fdx = zero, fdy = zero;
        if (local) {
            fdx = local_damping(vx_old, fx, alpha, minus_alpha);
            fdy = local_damping(vy_old, fy, alpha, minus_alpha);
            fx = _mm256_add_pd(fx, fdx);
            fy = _mm256_add_pd(fy, fdy);
        }
        const __m256d s = _mm256_mul_pd(inv_mass, dt);
        vx = _mm256_add_pd(vx, _mm256_mul_pd(fx, s));
        vy = _mm256_add_pd(vy, _mm256_mul_pd(fy, s));
        // the local damping's centred work, as the scalar loop: 0.0 - 0.5 fd.(v_old + v_new) dt,
        // less the rotation's below
        __m256d diss_local = zero;
        if (local) {
            const __m256d dot = _mm256_add_pd(_mm256_mul_pd(fdx, _mm256_add_pd(vx_old, vx)), _mm256_mul_pd(fdy, _mm256_add_pd(vy_old, vy)));
            diss_local = _mm256_sub_pd(zero, _mm256_mul_pd(_mm256_mul_pd(half, dot), dt));
        }
        px = _mm256_add_pd(px, _mm256_mul_pd(vx, dt));
        py = _mm256_add_pd(py, _mm256_mul_pd(vy, dt));
        store_xy(vel_a, i0, n, vx, vy);
        store_xy(pos_a, i0, n, px, py);
        speed_l1 = _mm256_max_pd(speed_l1, _mm256_add_pd(_mm256_andnot_pd(sign, vx), _mm256_andnot_pd(sign, vy)));
        extent_l1 = _mm256_max_pd(extent_l1, _mm256_add_pd(_mm256_andnot_pd(sign, px), _mm256_andnot_pd(sign, py)));

        // the kinetic energy after the step, translation then rotation (World::integrate_discs)
        __m256d kinetic = _mm256_mul_pd(_mm256_mul_pd(half, mass),
                                        _mm256_add_pd(_mm256_mul_pd(vx, vx), _mm256_mul_pd(vy, vy)));

        // rotation
        __m256d diss_rot = zero;
        if (rotation_model != 1)
            diss_rot = rotate_group(ld, omega_a, angle_a, inv_inertia_a, rr_factor_a, i0, n, inv_mass, inertia,
                                    rotation_consts, diss_local, kinetic);
        ledger_group(ld, diss_rot, diss_local, kinetic, i0, n, local, end, block_size, blocks, ledger);
        // the lanes beyond n repeat the last disc: not counted
        const __m256i valid_lanes = _mm256_cmpgt_epi64(_mm256_set1_epi64x(int64_t(n)), _mm256_setr_epi64x(0, 1, 2, 3));
        touching = _mm256_add_epi64(touching, _mm256_and_si256(valid_lanes, _mm256_and_si256(ld.counts, _mm256_set1_epi64x(0xffffffffLL))));

        // outside the domain or not a number; left the fat box
        const int valid = (1 << n) - 1;
        const __m256d inside = _mm256_and_pd(
            _mm256_and_pd(_mm256_cmp_pd(px, lo_x, _CMP_GE_OQ), _mm256_cmp_pd(px, hi_x, _CMP_LE_OQ)),
            _mm256_and_pd(_mm256_cmp_pd(py, lo_y, _CMP_GE_OQ), _mm256_cmp_pd(py, hi_y, _CMP_LE_OQ)));
        const int bad = ~_mm256_movemask_pd(inside) & valid;
        if (bad != 0 && out.fault == SIZE_MAX) out.fault = i0 + size_t(__builtin_ctz(unsigned(bad)));
        if (!out.any_escaped) {
            __m256d flo_x, flo_y, fhi_x, fhi_y;
            load_xy(fat_lo_a, i0, n, flo_x, flo_y);
            load_xy(fat_hi_a, i0, n, fhi_x, fhi_y);
            const __m256d in_box = _mm256_and_pd(
                _mm256_and_pd(_mm256_cmp_pd(flo_x, _mm256_sub_pd(px, radius), _CMP_LE_OQ),
                              _mm256_cmp_pd(flo_y, _mm256_sub_pd(py, radius), _CMP_LE_OQ)),
                _mm256_and_pd(_mm256_cmp_pd(_mm256_add_pd(px, radius), fhi_x, _CMP_LE_OQ),
                              _mm256_cmp_pd(_mm256_add_pd(py, radius), fhi_y, _CMP_LE_OQ)));
            out.any_escaped = (~_mm256_movemask_pd(in_box) & valid) != 0;
        }
    };
    size_t i0 = begin;
    for (; i0 + 4 <= end; i0 += 4) group(i0, 4);
    if (i0 < end) group(i0, end - i0);
    {
        alignas(32) double sp[4], ex[4];
        _mm256_store_pd(sp, speed_l1);
        _mm256_store_pd(ex, extent_l1);
        for (int l = 0; l < 4; ++l) {
            out.speed_l1 = std::max(out.speed_l1, sp[l]);
            out.extent_l1 = std::max(out.extent_l1, ex[l]);
        }
        alignas(32) int64_t t[4];
        _mm256_store_si256(reinterpret_cast<__m256i*>(t), touching);
        out.touching_dd = long(t[0] + t[1] + t[2] + t[3]);
    }
    if (p.auto_dt) {
        alignas(32) double b[4];
        _mm256_store_pd(b, best_sq);
        for (double x : b) out.best_sq = std::min(out.best_sq, x);
    }
    return out;
}
#else
IntegrateOut integrate_avx2(const IntegrateArrays&, const IntegrateParams&, size_t, size_t, LedgerBlock*, size_t) {
    return {INFINITY, SIZE_MAX, false};
}
#endif

}  // namespace demlab
