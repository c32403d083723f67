// integrate_kernel.h: World::integrate_discs' loop eight discs at a time in AVX-512 registers,
// for the CPUs that have AVX-512 (F, DQ, VL); integrate_avx2.cpp has the same operations on
// four discs, and the comments. Why: the AVX2 loop ran at about four instructions a cycle
// (perf: its samples spread over its instructions), so halving its vector instructions is
// what can make it faster. Same bits as the scalar loop and the AVX2 one: each lane does the
// same operations in the same order (no FMA: this file is compiled with -ffp-contract=off,
// CMakeLists.txt, and no intrinsic here fuses), the selects become masked blends on the same
// conditions, the ledger's sums are added disc by disc, and the kinetic energy goes into four
// lanes, disc i into lane i % 4 (a group's first four discs, then its last four), as
// LedgerBlock says. The last group of a range may hold fewer than eight discs: its missing
// lanes repeat the last disc and are not stored.
#include <immintrin.h>

#include <algorithm>
#include <cmath>

#include "dem/integrate_kernel.h"

// GCC 12's AVX-512 intrinsics pass an _mm512_undefined_pd() operand to their masked builtins,
// and -Wmaybe-uninitialized reports it wherever they are inlined (GCC bug 105593): a false
// positive of the compiler's own headers, silenced for this file only (as pair_kernel_avx512.cpp).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace demlab {

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define DEMLAB_AVX512 [[gnu::target("avx2,avx512f,avx512dq,avx512vl"), gnu::always_inline]] static inline
#define DEMLAB_AVX512_LAMBDA __attribute__((target("avx2,avx512f,avx512dq,avx512vl"), always_inline))

namespace {

// lane l reads index i0 + min(l, n - 1)
DEMLAB_AVX512 size_t lane(size_t i0, size_t n, size_t l) { return i0 + std::min(l, n - 1); }

// lanes 0 .. n-1
DEMLAB_AVX512 __mmask8 first_lanes(size_t n) { return __mmask8((1u << n) - 1u); }

DEMLAB_AVX512 __m512d load_lanes(const double* a, size_t i0, size_t n) {
    if (n == 8) return _mm512_loadu_pd(a + i0);
    return _mm512_set_pd(a[lane(i0, n, 7)], a[lane(i0, n, 6)], a[lane(i0, n, 5)], a[lane(i0, n, 4)], a[lane(i0, n, 3)],
                         a[lane(i0, n, 2)], a[lane(i0, n, 1)], a[i0]);
}

DEMLAB_AVX512 void store_lanes(double* a, size_t i0, size_t n, __m512d v) {
    if (n == 8)
        _mm512_storeu_pd(a + i0, v);
    else
        _mm512_mask_storeu_pd(a + i0, first_lanes(n), v);
}

// eight Vec2 as an x and a y register
DEMLAB_AVX512 void load_xy(const Vec2* a, size_t i0, size_t n, __m512d& x, __m512d& y) {
    if (n == 8) {
        const __m512d a03 = _mm512_loadu_pd(a[i0].data()), a47 = _mm512_loadu_pd(a[i0 + 4].data());  // x0 y0 x1 y1 ..
        x = _mm512_permutex2var_pd(a03, _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14), a47);
        y = _mm512_permutex2var_pd(a03, _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15), a47);
        return;
    }
    const Vec2 *p[8];
    for (size_t l = 0; l < 8; ++l) p[l] = &a[lane(i0, n, l)];
    x = _mm512_set_pd(p[7]->x(), p[6]->x(), p[5]->x(), p[4]->x(), p[3]->x(), p[2]->x(), p[1]->x(), p[0]->x());
    y = _mm512_set_pd(p[7]->y(), p[6]->y(), p[5]->y(), p[4]->y(), p[3]->y(), p[2]->y(), p[1]->y(), p[0]->y());
}

DEMLAB_AVX512 void store_xy(Vec2* a, size_t i0, size_t n, __m512d x, __m512d y) {
    const __m512d a03 = _mm512_permutex2var_pd(x, _mm512_setr_epi64(0, 8, 1, 9, 2, 10, 3, 11), y);    // x0 y0 .. x3 y3
    const __m512d a47 = _mm512_permutex2var_pd(x, _mm512_setr_epi64(4, 12, 5, 13, 6, 14, 7, 15), y);  // x4 y4 .. x7 y7
    if (n == 8) {
        _mm512_storeu_pd(a[i0].data(), a03);
        _mm512_storeu_pd(a[i0 + 4].data(), a47);
        return;
    }
    _mm512_mask_storeu_pd(a[i0].data(), first_lanes(2 * std::min<size_t>(n, 4)), a03);
    if (n > 4) _mm512_mask_storeu_pd(a[i0 + 4].data(), first_lanes(2 * (n - 4)), a47);
}

// c ? a : b, lane by lane
DEMLAB_AVX512 __m512d blend(__mmask8 c, __m512d a, __m512d b) { return _mm512_mask_blend_pd(c, b, a); }

DEMLAB_AVX512 __m512d neg(__m512d a) { return _mm512_xor_pd(a, _mm512_set1_pd(-0.0)); }

// Eight discs' loads (DiscLoad, one 64-byte record each, rows[l] lane l's disc) as eight
// registers of fields, by an 8x8 transpose: fx, fy, torque, k_tran, k_rot, dissipated,
// wall_normal and the two counts (n_disc in the low, n_wall in the high 32 bits of a lane).
struct LoadLanes {
    __m512d fx, fy, torque, k_tran, k_rot, dissipated, wall_normal;
    __m512i counts;
};

DEMLAB_AVX512 LoadLanes load_loads(const DiscLoad* const rows[8]) {
    static_assert(sizeof(DiscLoad) == 64 && alignof(DiscLoad) == 64);
    static_assert(offsetof(DiscLoad, force) == 0 && offsetof(DiscLoad, torque) == 16 && offsetof(DiscLoad, k_tran) == 24 &&
                  offsetof(DiscLoad, k_rot) == 32 && offsetof(DiscLoad, dissipated) == 40 &&
                  offsetof(DiscLoad, wall_normal) == 48 && offsetof(DiscLoad, n_disc) == 56 &&
                  offsetof(DiscLoad, n_wall) == 60);
    __m512d r[8];
    for (int l = 0; l < 8; ++l) r[l] = _mm512_load_pd(reinterpret_cast<const double*>(rows[l]));
    // pairs of rows: lo (fields 0 2 4 6 of rows 2k, 2k+1 side by side), hi (fields 1 3 5 7)
    const __m512d t0 = _mm512_unpacklo_pd(r[0], r[1]), t1 = _mm512_unpackhi_pd(r[0], r[1]);
    const __m512d t2 = _mm512_unpacklo_pd(r[2], r[3]), t3 = _mm512_unpackhi_pd(r[2], r[3]);
    const __m512d t4 = _mm512_unpacklo_pd(r[4], r[5]), t5 = _mm512_unpackhi_pd(r[4], r[5]);
    const __m512d t6 = _mm512_unpacklo_pd(r[6], r[7]), t7 = _mm512_unpackhi_pd(r[6], r[7]);
    // 128-bit lanes: t0 = (f0 of rows 0 1, f2 of 0 1, f4 of 0 1, f6 of 0 1); 0x88 takes lanes
    // 0 and 2 of each operand, 0xDD lanes 1 and 3
    const __m512d u04 = _mm512_shuffle_f64x2(t0, t2, 0x88), u26 = _mm512_shuffle_f64x2(t0, t2, 0xDD);  // rows 0-3
    const __m512d v04 = _mm512_shuffle_f64x2(t4, t6, 0x88), v26 = _mm512_shuffle_f64x2(t4, t6, 0xDD);  // rows 4-7
    const __m512d u15 = _mm512_shuffle_f64x2(t1, t3, 0x88), u37 = _mm512_shuffle_f64x2(t1, t3, 0xDD);
    const __m512d v15 = _mm512_shuffle_f64x2(t5, t7, 0x88), v37 = _mm512_shuffle_f64x2(t5, t7, 0xDD);
    LoadLanes o;
    o.fx = _mm512_shuffle_f64x2(u04, v04, 0x88);
    o.k_rot = _mm512_shuffle_f64x2(u04, v04, 0xDD);
    o.torque = _mm512_shuffle_f64x2(u26, v26, 0x88);
    o.wall_normal = _mm512_shuffle_f64x2(u26, v26, 0xDD);
    o.fy = _mm512_shuffle_f64x2(u15, v15, 0x88);
    o.dissipated = _mm512_shuffle_f64x2(u15, v15, 0xDD);
    o.k_tran = _mm512_shuffle_f64x2(u37, v37, 0x88);
    o.counts = _mm512_castpd_si512(_mm512_shuffle_f64x2(u37, v37, 0xDD));
    return o;
}

// local damping of a force or torque f against a velocity v (eq. 2.51), as the scalar loop:
// v > 0 ? -alpha |f| : (v < 0 ? alpha |f| : 0); a NaN velocity gives 0 there too
DEMLAB_AVX512 __m512d local_damping(__m512d v, __m512d f, __m512d alpha, __m512d minus_alpha) {
    const __m512d abs_f = _mm512_andnot_pd(_mm512_set1_pd(-0.0), f);
    const __m512d zero = _mm512_setzero_pd();
    return blend(_mm512_cmp_pd_mask(v, zero, _CMP_GT_OQ), _mm512_mul_pd(minus_alpha, abs_f),
                 blend(_mm512_cmp_pd_mask(v, zero, _CMP_LT_OQ), _mm512_mul_pd(alpha, abs_f), zero));
}

// lanes with n_disc > 0, and with n_wall > 0 (integrate_avx2.cpp)
DEMLAB_AVX512 __mmask8 touches_disc(__m512i counts) {
    return _mm512_cmpgt_epi64_mask(_mm512_slli_epi64(counts, 32), _mm512_setzero_si512());
}
DEMLAB_AVX512 __mmask8 touches_wall(__m512i counts) {
    return _mm512_cmpgt_epi64_mask(counts, _mm512_set1_epi64(0xffffffffLL));
}

// The critical step of a group (integrate_avx2.cpp: a group none of whose lanes can win
// skips the divisions) into best_sq.
struct StepConsts {
    __m512d zero, phi_sq, phi_t_sq, widen, smallest_normal, def_tran_one, def_rot_one;
    bool one_material, rotation_free;
    const int32_t* material;
    const double* default_k_tran;
    const double* default_k_rot;
};
DEMLAB_AVX512 void critical_step_group(const LoadLanes& ld, __m512d mass, __m512d inertia, __m512d radius, size_t i0,
                                       size_t n, const StepConsts& k, __m512d& best_sq) {
    const __m512d zero = k.zero, phi_sq = k.phi_sq, phi_t_sq = k.phi_t_sq, widen = k.widen;
    const __m512d smallest_normal = k.smallest_normal, def_tran_one = k.def_tran_one, def_rot_one = k.def_rot_one;
    const bool one_material = k.one_material, rotation_free = k.rotation_free;
    const int32_t* const material = k.material;
    const double* const default_k_tran = k.default_k_tran;
    const double* const default_k_rot = k.default_k_rot;
    __m512d def_tran = def_tran_one, def_rot = def_rot_one;
    if (!one_material) {
        const int32_t* m = material;
        alignas(64) double t[8], r[8];
        for (size_t l = 0; l < 8; ++l) {
            t[l] = default_k_tran[m[lane(i0, n, l)]];
            r[l] = default_k_rot[m[lane(i0, n, l)]];
        }
        def_tran = _mm512_load_pd(t);
        def_rot = _mm512_load_pd(r);
    }
    const __m512d kt = blend(_mm512_cmp_pd_mask(ld.k_tran, zero, _CMP_GT_OQ), ld.k_tran, def_tran);
    const __m512d kr = blend(_mm512_cmp_pd_mask(ld.k_rot, zero, _CMP_GT_OQ), ld.k_rot, def_rot);
    const __m512d a_t = _mm512_mul_pd(phi_t_sq, mass);
    const __m512d a_r = _mm512_mul_pd(phi_sq, inertia), b_r = _mm512_mul_pd(_mm512_mul_pd(kr, radius), radius);
    const __m512d p_t = _mm512_mul_pd(best_sq, kt);
    __mmask8 cannot_win = _mm512_cmp_pd_mask(a_t, _mm512_mul_pd(p_t, widen), _CMP_GE_OQ) &
                          _mm512_cmp_pd_mask(p_t, smallest_normal, _CMP_GE_OQ);
    if (rotation_free) {
        const __m512d p_r = _mm512_mul_pd(best_sq, b_r);
        cannot_win = __mmask8(cannot_win & _mm512_cmp_pd_mask(a_r, _mm512_mul_pd(p_r, widen), _CMP_GE_OQ) &
                              _mm512_cmp_pd_mask(p_r, smallest_normal, _CMP_GE_OQ));
    }
    if (cannot_win != 0xFF) {
        __m512d t2 = _mm512_div_pd(a_t, kt);
        if (rotation_free) {
            const __m512d r2 = _mm512_div_pd(a_r, b_r);
            t2 = blend(_mm512_cmp_pd_mask(r2, t2, _CMP_LT_OQ), r2, t2);
        }
        best_sq = _mm512_min_pd(t2, best_sq);
    }
}

// The rotation of a group (integrate_avx2.cpp's rotate_group, eight lanes).
struct RotationConsts {
    __m512d dt, zero, half, alpha, minus_alpha, g_abs, mu_br;
    bool local, rolling_literal;
    int rotation_model;
};
DEMLAB_AVX512 __m512d rotate_group(const LoadLanes& ld, double* omega_a, double* angle_a, const double* inv_inertia_a,
                                   const double* rr_factor_a, size_t i0, size_t n, __m512d inv_mass, __m512d inertia,
                                   const RotationConsts& k, __m512d& diss_local, __m512d& kinetic) {
    const __m512d dt = k.dt, zero = k.zero, half = k.half, alpha = k.alpha, minus_alpha = k.minus_alpha;
    const __m512d g_abs = k.g_abs, mu_br = k.mu_br;
    const bool local = k.local, rolling_literal = k.rolling_literal;
    const int rotation_model = k.rotation_model;
    __m512d diss_rot = zero;
    const __m512d tq = ld.torque;
    const __m512d w_old = load_lanes(omega_a, i0, n);
    __m512d tq_damped = tq, td = zero;
    if (local) {
        td = local_damping(w_old, tq, alpha, minus_alpha);
        tq_damped = _mm512_add_pd(tq, td);
    }
    const __m512d w_free =
        _mm512_add_pd(w_old, _mm512_mul_pd(_mm512_mul_pd(tq_damped, load_lanes(inv_inertia_a, i0, n)), dt));
    if (local)
        diss_local = _mm512_sub_pd(diss_local, _mm512_mul_pd(_mm512_mul_pd(_mm512_mul_pd(half, td), _mm512_add_pd(w_old, w_free)), dt));
    __m512d w = w_free;
    const __m512d rr = load_lanes(rr_factor_a, i0, n);
    const __mmask8 rolling = touches_wall(ld.counts) & _mm512_cmp_pd_mask(rr, zero, _CMP_GT_OQ);
    if (rolling != 0) {
        const __m512d g_eff = rolling_literal ? g_abs : _mm512_mul_pd(ld.wall_normal, inv_mass);
        const __m512d delta = _mm512_mul_pd(_mm512_mul_pd(g_eff, rr), dt);
        const __m512d reduced =
            blend(_mm512_cmp_pd_mask(w, delta, _CMP_GT_OQ), _mm512_sub_pd(w, delta),
                  blend(_mm512_cmp_pd_mask(w, neg(delta), _CMP_LT_OQ), _mm512_add_pd(w, delta), zero));
        w = blend(rolling, reduced, w);
    }
    if (rotation_model == 3) w = blend(touches_disc(ld.counts), _mm512_mul_pd(w, mu_br), w);
    const __m512d taken =
        _mm512_mul_pd(_mm512_mul_pd(half, inertia), _mm512_sub_pd(_mm512_mul_pd(w_free, w_free), _mm512_mul_pd(w, w)));
    const __m512d torque_work = _mm512_mul_pd(_mm512_mul_pd(_mm512_mul_pd(half, tq), dt), _mm512_sub_pd(w_free, w));
    diss_rot = _mm512_add_pd(zero, _mm512_sub_pd(taken, torque_work));
    kinetic = _mm512_add_pd(kinetic, _mm512_mul_pd(_mm512_mul_pd(half, inertia), _mm512_mul_pd(w, w)));
    store_lanes(omega_a, i0, n, w);
    store_lanes(angle_a, i0, n, _mm512_add_pd(load_lanes(angle_a, i0, n), _mm512_mul_pd(w, dt)));
    return diss_rot;
}

// The ledger's terms of a group, disc by disc; a block's sums are written when its last disc
// is added. The kinetic energy: the group's first four discs, then its last four, as two
// groups of the AVX2 loop (the lanes beyond n add +0: the lanes hold +0 or more, so no bit
// changes).
struct LedgerSums {
    double sum_contacts, sum_rotation, sum_local;
    __m256d kinetic_lanes;
    size_t block, block_end;
};
DEMLAB_AVX512 void ledger_group(const LoadLanes& ld, __m512d diss_rot, __m512d diss_local, __m512d kinetic, size_t i0,
                                size_t n, __mmask8 valid, bool local, size_t end, size_t block_size, LedgerBlock* blocks,
                                LedgerSums& L) {
    double& sum_contacts = L.sum_contacts;
    double& sum_rotation = L.sum_rotation;
    double& sum_local = L.sum_local;
    __m256d& kinetic_lanes = L.kinetic_lanes;
    size_t& block = L.block;
    size_t& block_end = L.block_end;
    // the ledger: the contacts' dissipation and the rotation rules' terms, disc by disc; a
    // block's sums are written when its last disc is added. The kinetic energy: the
    // group's first four discs, then its last four, as two groups of the AVX2 loop (the
    // lanes beyond n add +0: the lanes hold +0 or more, so no bit changes)
    alignas(64) double diss_terms[8], rot_terms[8], local_terms[8];
    _mm512_store_pd(diss_terms, ld.dissipated);
    _mm512_store_pd(rot_terms, diss_rot);
    _mm512_store_pd(local_terms, diss_local);
    const __m512d kinetic_valid = _mm512_maskz_mov_pd(valid, kinetic);
    if (n == 8 && i0 + 8 < block_end) {
        kinetic_lanes = _mm256_add_pd(kinetic_lanes, _mm512_castpd512_pd256(kinetic_valid));
        kinetic_lanes = _mm256_add_pd(kinetic_lanes, _mm512_extractf64x4_pd(kinetic_valid, 1));
        for (size_t l = 0; l < 8; ++l) {
            sum_contacts += diss_terms[l];
            sum_rotation += rot_terms[l];
        }
        if (local)
            for (size_t l = 0; l < 8; ++l) sum_local += local_terms[l];
    } else {
        for (size_t half_start = 0; half_start < n; half_start += 4) {
            kinetic_lanes = _mm256_add_pd(kinetic_lanes, half_start == 0 ? _mm512_castpd512_pd256(kinetic_valid)
                                                                         : _mm512_extractf64x4_pd(kinetic_valid, 1));
            for (size_t l = half_start; l < std::min(n, half_start + 4); ++l) {
                sum_contacts += diss_terms[l];
                sum_rotation += rot_terms[l];
                sum_local += local_terms[l];
                if (i0 + l + 1 == block_end) {
                    LedgerBlock& b = blocks[block];
                    b.contacts = sum_contacts;
                    b.local = sum_local;
                    b.rotation = sum_rotation;
                    alignas(32) double k[4];
                    _mm256_store_pd(k, kinetic_lanes);
                    b.kinetic = (k[0] + k[1]) + (k[2] + k[3]);
                    kinetic_lanes = _mm256_setzero_pd();
                    sum_contacts = sum_rotation = sum_local = 0.0;
                    ++block;
                    block_end = std::min(block_end + block_size, end);
                }
            }
        }
    }
}

}  // namespace

[[gnu::target("avx2,avx512f,avx512dq,avx512vl")]] IntegrateOut integrate_avx512(const IntegrateArrays& a,
                                                                              const IntegrateParams& p, size_t begin,
                                                                              size_t end, LedgerBlock* blocks,
                                                                              size_t block_size) {
    const __m512d dt = _mm512_set1_pd(p.dt);
    const __m512d gx = _mm512_set1_pd(p.g.x()), gy = _mm512_set1_pd(p.g.y());
    const __m512d zero = _mm512_setzero_pd(), half = _mm512_set1_pd(0.5);
    const __m512d lo_x = _mm512_set1_pd(p.domain_lo.x()), lo_y = _mm512_set1_pd(p.domain_lo.y());
    const __m512d hi_x = _mm512_set1_pd(p.domain_hi.x()), hi_y = _mm512_set1_pd(p.domain_hi.y());
    const __m512d phi_sq = _mm512_set1_pd(p.phi_sq), phi_t_sq = _mm512_set1_pd(p.phi_t_sq);
    const __m512d g_abs = _mm512_set1_pd(p.g_abs), mu_br = _mm512_set1_pd(p.mu_br);
    const bool one_material = a.n_materials == 1;
    const __m512d def_tran_one = _mm512_set1_pd(a.default_k_tran[0]), def_rot_one = _mm512_set1_pd(a.default_k_rot[0]);
    __m512d best_sq = _mm512_set1_pd(p.auto_dt ? p.best_sq_start : INFINITY);
    const __m512d widen = _mm512_set1_pd(1.0 + 0x1p-51), smallest_normal = _mm512_set1_pd(0x1p-1022);
    const __m512d sign = _mm512_set1_pd(-0.0);
    __m512d speed_l1 = zero, extent_l1 = zero;
    IntegrateOut out{INFINITY, SIZE_MAX, false, 0.0, 0.0, 0};
    // local damping (eq. 2.51), as the scalar loop: F_d = -alpha |F| sign(v) per degree of freedom
    const bool local = p.alpha > 0.0;
    const __m512d alpha = _mm512_set1_pd(p.alpha), minus_alpha = _mm512_set1_pd(-p.alpha);
    // the ledger's sums; the kinetic energy in four lanes, disc i in lane i % 4, as the AVX2
    // loop has it: a group's first four discs are added, then its last four (begin is a
    // multiple of 4)
    LedgerSums ledger{0.0, 0.0, 0.0, _mm256_setzero_pd(), begin / block_size,
                      std::min((begin / block_size + 1) * block_size, end)};
    __m512i touching = _mm512_setzero_si512();

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

    auto group = [&](size_t i0, size_t n) DEMLAB_AVX512_LAMBDA {
        const DiscLoad* rows[8];
        for (size_t l = 0; l < 8; ++l) rows[l] = loads + lane(i0, n, l);
        const LoadLanes ld = load_loads(rows);
        const __m512d mass = load_lanes(mass_a, i0, n), inv_mass = load_lanes(inv_mass_a, i0, n);
        const __m512d inertia = load_lanes(inertia_a, i0, n), radius = load_lanes(radius_a, i0, n);

        if (auto_dt) critical_step_group(ld, mass, inertia, radius, i0, n, step_consts, best_sq);

        // translation: v += (F + m g) / m dt, x += v dt
        __m512d fx = _mm512_add_pd(ld.fx, _mm512_mul_pd(mass, gx));
        __m512d fy = _mm512_add_pd(ld.fy, _mm512_mul_pd(mass, gy));
        __m512d vx, vy, px, py;
        load_xy(vel_a, i0, n, vx, vy);
        load_xy(pos_a, i0, n, px, py);
        const __m512d vx_old = vx, vy_old = vy;
        __m512d fdx = zero, fdy = zero;
        if (local) {
            fdx = local_damping(vx_old, fx, alpha, minus_alpha);
            fdy = local_damping(vy_old, fy, alpha, minus_alpha);
            fx = _mm512_add_pd(fx, fdx);
            fy = _mm512_add_pd(fy, fdy);
        }
        const __m512d s = _mm512_mul_pd(inv_mass, dt);
        vx = _mm512_add_pd(vx, _mm512_mul_pd(fx, s));
        vy = _mm512_add_pd(vy, _mm512_mul_pd(fy, s));
        // the local damping's centred work: 0.0 - 0.5 fd.(v_old + v_new) dt, and the rotation's below
        __m512d diss_local = zero;
        if (local) {
            const __m512d dot = _mm512_add_pd(_mm512_mul_pd(fdx, _mm512_add_pd(vx_old, vx)), _mm512_mul_pd(fdy, _mm512_add_pd(vy_old, vy)));
            diss_local = _mm512_sub_pd(zero, _mm512_mul_pd(_mm512_mul_pd(half, dot), dt));
        }
        px = _mm512_add_pd(px, _mm512_mul_pd(vx, dt));
        py = _mm512_add_pd(py, _mm512_mul_pd(vy, dt));
        store_xy(vel_a, i0, n, vx, vy);
        store_xy(pos_a, i0, n, px, py);
        speed_l1 = _mm512_max_pd(speed_l1, _mm512_add_pd(_mm512_andnot_pd(sign, vx), _mm512_andnot_pd(sign, vy)));
        extent_l1 = _mm512_max_pd(extent_l1, _mm512_add_pd(_mm512_andnot_pd(sign, px), _mm512_andnot_pd(sign, py)));

        __m512d kinetic = _mm512_mul_pd(_mm512_mul_pd(half, mass), _mm512_add_pd(_mm512_mul_pd(vx, vx), _mm512_mul_pd(vy, vy)));

        // rotation
        __m512d diss_rot = zero;
        if (rotation_model != 1)
            diss_rot = rotate_group(ld, omega_a, angle_a, inv_inertia_a, rr_factor_a, i0, n, inv_mass, inertia,
                                    rotation_consts, diss_local, kinetic);
        const __mmask8 valid = first_lanes(n);
        ledger_group(ld, diss_rot, diss_local, kinetic, i0, n, valid, local, end, block_size, blocks, ledger);
        touching = _mm512_add_epi64(touching, _mm512_maskz_and_epi64(valid, ld.counts, _mm512_set1_epi64(0xffffffffLL)));

        // outside the domain or not a number; left the fat box
        const __mmask8 inside = _mm512_cmp_pd_mask(px, lo_x, _CMP_GE_OQ) & _mm512_cmp_pd_mask(px, hi_x, _CMP_LE_OQ) &
                                _mm512_cmp_pd_mask(py, lo_y, _CMP_GE_OQ) & _mm512_cmp_pd_mask(py, hi_y, _CMP_LE_OQ);
        const unsigned bad = unsigned(__mmask8(~inside & valid));
        if (bad != 0 && out.fault == SIZE_MAX) out.fault = i0 + size_t(__builtin_ctz(bad));
        if (!out.any_escaped) {
            __m512d flo_x, flo_y, fhi_x, fhi_y;
            load_xy(fat_lo_a, i0, n, flo_x, flo_y);
            load_xy(fat_hi_a, i0, n, fhi_x, fhi_y);
            const __mmask8 in_box = _mm512_cmp_pd_mask(flo_x, _mm512_sub_pd(px, radius), _CMP_LE_OQ) &
                                    _mm512_cmp_pd_mask(flo_y, _mm512_sub_pd(py, radius), _CMP_LE_OQ) &
                                    _mm512_cmp_pd_mask(_mm512_add_pd(px, radius), fhi_x, _CMP_LE_OQ) &
                                    _mm512_cmp_pd_mask(_mm512_add_pd(py, radius), fhi_y, _CMP_LE_OQ);
            out.any_escaped = __mmask8(~in_box & valid) != 0;
        }
    };
    size_t i0 = begin;
    for (; i0 + 8 <= end; i0 += 8) group(i0, 8);
    if (i0 < end) group(i0, end - i0);
    {
        alignas(64) double sp[8], ex[8];
        _mm512_store_pd(sp, speed_l1);
        _mm512_store_pd(ex, extent_l1);
        for (int l = 0; l < 8; ++l) {
            out.speed_l1 = std::max(out.speed_l1, sp[l]);
            out.extent_l1 = std::max(out.extent_l1, ex[l]);
        }
        alignas(64) int64_t t[8];
        _mm512_store_si512(t, touching);
        long sum = 0;
        for (int64_t x : t) sum += long(x);
        out.touching_dd = sum;
    }
    if (p.auto_dt) {
        alignas(64) double b[8];
        _mm512_store_pd(b, best_sq);
        for (double x : b) out.best_sq = std::min(out.best_sq, x);
    }
    return out;
}
#else
IntegrateOut integrate_avx512(const IntegrateArrays&, const IntegrateParams&, size_t, size_t, LedgerBlock*, size_t) {
    return {INFINITY, SIZE_MAX, false, 0.0, 0.0, 0};
}
#endif

}  // namespace demlab
