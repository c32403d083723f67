// integrate_kernel.h: World::integrate_discs' loop four discs at a time. Same bits as the
// scalar loop: each lane does its operations in its order (no FMA: the functions ask for
// "avx2" only), the conditions become blends, and the ledger's terms go back to the caller to
// be added in disc order. The last group of a range may hold fewer than four discs: its
// missing lanes repeat the last disc and are not stored.
#include <immintrin.h>

#include <algorithm>
#include <cmath>

#include "integrate_kernel.h"

namespace demlab {

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define DEMLAB_AVX2 [[gnu::target("avx2"), gnu::always_inline]] static inline

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

// a field of the four discs' loads
template <typename F>
DEMLAB_AVX2 __m256d load_field(const DiscLoad* load, size_t i0, size_t n, F field) {
    return _mm256_set_pd(field(load[lane(i0, n, 3)]), field(load[lane(i0, n, 2)]), field(load[lane(i0, n, 1)]),
                         field(load[i0]));
}

// lanes whose count is above zero, as a mask
template <typename F>
DEMLAB_AVX2 __m256d positive_count(const DiscLoad* load, size_t i0, size_t n, F count) {
    const __m128i c = _mm_set_epi32(count(load[lane(i0, n, 3)]), count(load[lane(i0, n, 2)]), count(load[lane(i0, n, 1)]),
                                    count(load[i0]));
    return _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_cmpgt_epi32(c, _mm_setzero_si128())));
}

// c ? a : b, lane by lane
DEMLAB_AVX2 __m256d blend(__m256d c, __m256d a, __m256d b) { return _mm256_blendv_pd(b, a, c); }

DEMLAB_AVX2 __m256d neg(__m256d a) { return _mm256_xor_pd(a, _mm256_set1_pd(-0.0)); }

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
    __m256d best_sq = _mm256_set1_pd(INFINITY);
    const __m256d sign = _mm256_set1_pd(-0.0);
    __m256d speed_l1 = zero, extent_l1 = zero;  // (a NaN is caught by the domain test)
    IntegrateOut out{INFINITY, SIZE_MAX, false, 0.0, 0.0, 0};
    // The ledger's sums, disc by disc in order as the scalar loops add them (two chains of
    // additions that run beside the vector work; as passes of their own after the loop they
    // cost 3 % of DB-9k's step, docs/performance.md)
    double sum_contacts = 0.0, sum_rotation = 0.0;
    long touching = 0;
    for (size_t i0 = begin; i0 < end; i0 += 4) {
        const size_t n = std::min<size_t>(4, end - i0);
        const DiscLoad* const ld = a.load;
        const __m256d mass = load_lanes(a.mass, i0, n), inv_mass = load_lanes(a.inv_mass, i0, n);
        const __m256d inertia = load_lanes(a.inertia, i0, n), radius = load_lanes(a.radius, i0, n);

        // the critical step (World::critical_step_squared_at; std::min(best, t) is min_pd(t, best))
        if (p.auto_dt) {
            const __m256d k_tran = load_field(ld, i0, n, [](const DiscLoad& l) { return l.k_tran; });
            const __m256d k_rot = load_field(ld, i0, n, [](const DiscLoad& l) { return l.k_rot; });
            const int32_t* m = a.material;
            const __m256d def_tran = _mm256_set_pd(a.default_k_tran[m[lane(i0, n, 3)]], a.default_k_tran[m[lane(i0, n, 2)]],
                                                   a.default_k_tran[m[lane(i0, n, 1)]], a.default_k_tran[m[i0]]);
            const __m256d def_rot = _mm256_set_pd(a.default_k_rot[m[lane(i0, n, 3)]], a.default_k_rot[m[lane(i0, n, 2)]],
                                                  a.default_k_rot[m[lane(i0, n, 1)]], a.default_k_rot[m[i0]]);
            const __m256d kt = blend(_mm256_cmp_pd(k_tran, zero, _CMP_GT_OQ), k_tran, def_tran);
            const __m256d kr = blend(_mm256_cmp_pd(k_rot, zero, _CMP_GT_OQ), k_rot, def_rot);
            __m256d t2 = _mm256_div_pd(_mm256_mul_pd(phi_t_sq, mass), kt);
            if (p.rotation_free) {
                const __m256d r2 =
                    _mm256_div_pd(_mm256_mul_pd(phi_sq, inertia), _mm256_mul_pd(_mm256_mul_pd(kr, radius), radius));
                t2 = blend(_mm256_cmp_pd(r2, t2, _CMP_LT_OQ), r2, t2);
            }
            best_sq = _mm256_min_pd(t2, best_sq);
        }

        // translation: v += (F + m g) / m dt, x += v dt
        const __m256d fx = _mm256_add_pd(load_field(ld, i0, n, [](const DiscLoad& l) { return l.force.x(); }),
                                         _mm256_mul_pd(mass, gx));
        const __m256d fy = _mm256_add_pd(load_field(ld, i0, n, [](const DiscLoad& l) { return l.force.y(); }),
                                         _mm256_mul_pd(mass, gy));
        __m256d vx, vy, px, py;
        load_xy(a.vel, i0, n, vx, vy);
        load_xy(a.pos, i0, n, px, py);
        const __m256d s = _mm256_mul_pd(inv_mass, dt);
        vx = _mm256_add_pd(vx, _mm256_mul_pd(fx, s));
        vy = _mm256_add_pd(vy, _mm256_mul_pd(fy, s));
        px = _mm256_add_pd(px, _mm256_mul_pd(vx, dt));
        py = _mm256_add_pd(py, _mm256_mul_pd(vy, dt));
        store_xy(a.vel, i0, n, vx, vy);
        store_xy(a.pos, i0, n, px, py);
        speed_l1 = _mm256_max_pd(speed_l1, _mm256_add_pd(_mm256_andnot_pd(sign, vx), _mm256_andnot_pd(sign, vy)));
        extent_l1 = _mm256_max_pd(extent_l1, _mm256_add_pd(_mm256_andnot_pd(sign, px), _mm256_andnot_pd(sign, py)));

        // rotation
        __m256d diss_rot = zero;
        if (p.rotation_model != 1) {
            const __m256d tq = load_field(ld, i0, n, [](const DiscLoad& l) { return l.torque; });
            const __m256d w_old = load_lanes(a.omega, i0, n);
            const __m256d w_free =
                _mm256_add_pd(w_old, _mm256_mul_pd(_mm256_mul_pd(tq, load_lanes(a.inv_inertia, i0, n)), dt));
            __m256d w = w_free;
            // Model 2/3: rolling resistance for a disc touching a wall (reduce_towards_zero)
            const __m256d rr = load_lanes(a.rr_factor, i0, n);
            const __m256d rolling = _mm256_and_pd(positive_count(ld, i0, n, [](const DiscLoad& l) { return l.n_wall; }),
                                                  _mm256_cmp_pd(rr, zero, _CMP_GT_OQ));
            if (_mm256_movemask_pd(rolling) != 0) {
                const __m256d g_eff =
                    p.rolling_literal
                        ? g_abs
                        : _mm256_mul_pd(load_field(ld, i0, n, [](const DiscLoad& l) { return l.wall_normal; }), inv_mass);
                const __m256d delta = _mm256_mul_pd(_mm256_mul_pd(g_eff, rr), dt);
                const __m256d reduced =
                    blend(_mm256_cmp_pd(w, delta, _CMP_GT_OQ), _mm256_sub_pd(w, delta),
                          blend(_mm256_cmp_pd(w, neg(delta), _CMP_LT_OQ), _mm256_add_pd(w, delta), zero));
                w = blend(rolling, reduced, w);
            }
            // Model 3: rotational damping of a disc touching another (per disc)
            if (p.rotation_model == 3)
                w = blend(positive_count(ld, i0, n, [](const DiscLoad& l) { return l.n_disc; }), _mm256_mul_pd(w, mu_br), w);
            const __m256d taken = _mm256_mul_pd(_mm256_mul_pd(half, inertia),
                                                _mm256_sub_pd(_mm256_mul_pd(w_free, w_free), _mm256_mul_pd(w, w)));
            const __m256d torque_work = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(half, tq), dt), _mm256_sub_pd(w_free, w));
            diss_rot = _mm256_add_pd(zero, _mm256_sub_pd(taken, torque_work));
            store_lanes(a.omega, i0, n, w);
            store_lanes(a.angle, i0, n, _mm256_add_pd(load_lanes(a.angle, i0, n), _mm256_mul_pd(w, dt)));
        }
        alignas(32) double rot_terms[4];
        _mm256_store_pd(rot_terms, diss_rot);
        for (size_t l = 0; l < n; ++l) {
            const size_t i = i0 + l;
            sum_contacts += ld[i].dissipated;
            sum_rotation += rot_terms[l];
            touching += ld[i].n_disc;
            if ((i + 1) % block_size == 0 || i + 1 == end) {
                LedgerBlock& b = blocks[i / block_size];
                b.contacts = sum_contacts;
                b.local = 0.0;  // no local damping in this loop
                b.rotation = sum_rotation;
                sum_contacts = sum_rotation = 0.0;
            }
        }

        // outside the domain or not a number; left the fat box
        const int valid = (1 << n) - 1;
        const __m256d inside = _mm256_and_pd(
            _mm256_and_pd(_mm256_cmp_pd(px, lo_x, _CMP_GE_OQ), _mm256_cmp_pd(px, hi_x, _CMP_LE_OQ)),
            _mm256_and_pd(_mm256_cmp_pd(py, lo_y, _CMP_GE_OQ), _mm256_cmp_pd(py, hi_y, _CMP_LE_OQ)));
        const int bad = ~_mm256_movemask_pd(inside) & valid;
        if (bad != 0 && out.fault == SIZE_MAX) out.fault = i0 + size_t(__builtin_ctz(unsigned(bad)));
        if (!out.any_escaped) {
            __m256d flo_x, flo_y, fhi_x, fhi_y;
            load_xy(a.fat_lo, i0, n, flo_x, flo_y);
            load_xy(a.fat_hi, i0, n, fhi_x, fhi_y);
            const __m256d in_box = _mm256_and_pd(
                _mm256_and_pd(_mm256_cmp_pd(flo_x, _mm256_sub_pd(px, radius), _CMP_LE_OQ),
                              _mm256_cmp_pd(flo_y, _mm256_sub_pd(py, radius), _CMP_LE_OQ)),
                _mm256_and_pd(_mm256_cmp_pd(_mm256_add_pd(px, radius), fhi_x, _CMP_LE_OQ),
                              _mm256_cmp_pd(_mm256_add_pd(py, radius), fhi_y, _CMP_LE_OQ)));
            out.any_escaped = (~_mm256_movemask_pd(in_box) & valid) != 0;
        }
    }
    {
        alignas(32) double sp[4], ex[4];
        _mm256_store_pd(sp, speed_l1);
        _mm256_store_pd(ex, extent_l1);
        for (int l = 0; l < 4; ++l) {
            out.speed_l1 = std::max(out.speed_l1, sp[l]);
            out.extent_l1 = std::max(out.extent_l1, ex[l]);
        }
    }
    out.touching_dd = touching;
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
