// The disc-disc kernel of pair_kernel.h, four pairs at a time in AVX2 registers.
//
// Same bits as disc_pair_force: every lane does the scalar kernel's operations in the scalar
// kernel's order, and IEEE addition, multiplication, division and square root are correctly
// rounded whatever the register width. Three things keep it so:
// - No FMA. The functions below ask for "avx2" only; with "fma" GCC would contract a * b + c
//   into one rounding (its default -ffp-contract=fast), and the bits would differ.
// - min/max in the order of std::min/std::max: std::max(a, b) is (a < b) ? b : a, which is
//   _mm256_max_pd(b, a) (it returns its first operand when that is greater, else the second),
//   so both agree on signed zeros and NaN.
// - The selects of contact_law.h become blends on the same conditions.
// The caller sums the batch's results into the discs in list order, as the scalar pass does
// (force_pass.cpp), so the sums are the same bits too.
//
// Only this file's functions use AVX2; the caller asks cpu_has_avx2() first.
#include <immintrin.h>

#include <cstddef>
#include <cstring>

#include "dem/laws/pair_kernel.h"
#include "dem/laws/pair_select_avx2.h"

namespace demlab {

bool cpu_has_avx2() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    return __builtin_cpu_supports("avx2");
#else
    return false;
#endif
}

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define DEMLAB_AVX2 [[gnu::target("avx2"), gnu::always_inline]] static inline

namespace {

using pair_select::load4;
using pair_select::load_xy;

// c ? a : b, lane by lane (c all ones or all zeros)
DEMLAB_AVX2 __m256d blend(__m256d c, __m256d a, __m256d b) { return _mm256_blendv_pd(b, a, c); }

DEMLAB_AVX2 __m256d neg(__m256d a) { return _mm256_xor_pd(a, _mm256_set1_pd(-0.0)); }

// Four registers whose lanes are pairs, as four records (rows[l] = lane l of a, b, c, d).
DEMLAB_AVX2 void store_rows(double (*rows)[4], __m256d a, __m256d b, __m256d c, __m256d d) {
    const __m256d ab02 = _mm256_unpacklo_pd(a, b), ab13 = _mm256_unpackhi_pd(a, b);
    const __m256d cd02 = _mm256_unpacklo_pd(c, d), cd13 = _mm256_unpackhi_pd(c, d);
    _mm256_store_pd(rows[0], _mm256_permute2f128_pd(ab02, cd02, 0x20));
    _mm256_store_pd(rows[1], _mm256_permute2f128_pd(ab13, cd13, 0x20));
    _mm256_store_pd(rows[2], _mm256_permute2f128_pd(ab02, cd02, 0x31));
    _mm256_store_pd(rows[3], _mm256_permute2f128_pd(ab13, cd13, 0x31));
}

// Four pairs' materials (PairMaterial) as lanes.
struct PairLanes {
    __m256d kn, ks, mu, inv_ks, k_tran;
};

DEMLAB_AVX2 PairLanes broadcast_lanes(const PairMaterial& m) {
    return {_mm256_set1_pd(m.kn), _mm256_set1_pd(m.ks), _mm256_set1_pd(m.mu), _mm256_set1_pd(m.inv_ks),
            _mm256_set1_pd(m.k_tran)};
}

DEMLAB_AVX2 PairLanes pair_lanes(const PairPassParams& p, const DiscArrays& d, size_t i0, size_t i1, size_t i2, size_t i3,
                                 size_t j0, size_t j1, size_t j2, size_t j3) {
    const PairMaterial* pm0 = &p.materials[size_t(d.material[i0]) * p.n_materials + size_t(d.material[j0])];
    const PairMaterial* pm1 = &p.materials[size_t(d.material[i1]) * p.n_materials + size_t(d.material[j1])];
    const PairMaterial* pm2 = &p.materials[size_t(d.material[i2]) * p.n_materials + size_t(d.material[j2])];
    const PairMaterial* pm3 = &p.materials[size_t(d.material[i3]) * p.n_materials + size_t(d.material[j3])];
    return {_mm256_set_pd(pm3->kn, pm2->kn, pm1->kn, pm0->kn), _mm256_set_pd(pm3->ks, pm2->ks, pm1->ks, pm0->ks),
            _mm256_set_pd(pm3->mu, pm2->mu, pm1->mu, pm0->mu),
            _mm256_set_pd(pm3->inv_ks, pm2->inv_ks, pm1->inv_ks, pm0->inv_ks),
            _mm256_set_pd(pm3->k_tran, pm2->k_tran, pm1->k_tran, pm0->k_tran)};
}

// The law for the contacts c + out.index[b], b < out.count (the list padded to a multiple of
// four), results into out in that order. Returns how many it did: out.count, or fewer when a
// group of four holds a blown-up pair: then it stops before that group (out.count is cut
// there) and writes nothing from there on, for the scalar kernel to report. With skip, the
// clearances of the pairs it does are marked.
template <bool kOneMaterial>
DEMLAB_AVX2 size_t law(const DiscArrays& d, const PairPassParams& p, DiscContact* c, PairBatch& out, const PairSkip* skip) {
    const PairLanes one = kOneMaterial ? broadcast_lanes(p.materials[0]) : PairLanes{};
    const double* pos = d.pos->data();
    const double* vel = d.vel->data();
    const bool no_tension = p.mode == DashpotMode::NoTension || p.mode == DashpotMode::NoTensionNoShearWhileSliding;
    const bool no_shear_sliding =
        p.mode == DashpotMode::NoShearWhileSliding || p.mode == DashpotMode::NoTensionNoShearWhileSliding;
    const __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    const __m256d zero = _mm256_setzero_pd();
    const __m256d no_tension_m = no_tension ? all : zero;
    const __m256d no_shear_sliding_m = no_shear_sliding ? all : zero;
    const __m256d half = _mm256_set1_pd(0.5);
    const __m256d dt = _mm256_set1_pd(p.dt), last_dt = _mm256_set1_pd(p.last_dt);
    const __m256d minus_half_last_dt = _mm256_set1_pd(-0.5 * p.last_dt);
    const __m256d ratio = _mm256_set1_pd(p.max_overlap_ratio);
    static_assert(offsetof(DiscContact, damp_s) == offsetof(DiscContact, damp_n) + sizeof(float));
    const size_t m = out.count;

    // 2. The law, four of those pairs at a time.
    for (size_t g = 0; g < m; g += 4) {
        DiscContact* const q[4] = {c + out.index[g], c + out.index[g + 1], c + out.index[g + 2], c + out.index[g + 3]};
        const size_t i0 = size_t(q[0]->i), i1 = size_t(q[1]->i), i2 = size_t(q[2]->i), i3 = size_t(q[3]->i);
        const size_t j0 = size_t(q[0]->j), j1 = size_t(q[1]->j), j2 = size_t(q[2]->j), j3 = size_t(q[3]->j);
        __m256d xi, yi, xj, yj;
        load_xy(pos, i0, i1, i2, i3, xi, yi);
        load_xy(pos, j0, j1, j2, j3, xj, yj);
        const __m256d ri = load4(d.radius, i0, i1, i2, i3), rj = load4(d.radius, j0, j1, j2, j3);
        const __m256d dxx = _mm256_sub_pd(xj, xi), dxy = _mm256_sub_pd(yj, yi);
        const __m256d rsum = _mm256_add_pd(ri, rj);
        const __m256d dist2 = _mm256_add_pd(_mm256_mul_pd(dxx, dxx), _mm256_mul_pd(dxy, dxy));
        // the scalar kernel's "dist2 >= rsum^2: open" negated (NaN counts as touching, as there)
        const __m256d touching = _mm256_cmp_pd(dist2, _mm256_mul_pd(rsum, rsum), _CMP_NGE_UQ);
        const __m256d dist = _mm256_sqrt_pd(dist2);
        const __m256d overlap = _mm256_sub_pd(rsum, dist);
        const __m256d fault =
            _mm256_and_pd(touching, _mm256_or_pd(_mm256_cmp_pd(overlap, _mm256_mul_pd(ratio, _mm256_min_pd(rj, ri)), _CMP_NLE_UQ),
                                                 _mm256_cmp_pd(dist, zero, _CMP_EQ_OQ)));
        // A blown-up pair: leave this group untouched and stop before its first pair; the
        // pairs left out before that one had nothing to do. The caller's scalar kernel
        // reports it.
        if (_mm256_movemask_pd(fault) != 0) {
            out.count = g;
            return g;
        }

        const __m256d nx = _mm256_div_pd(dxx, dist), ny = _mm256_div_pd(dxy, dist);
        const __m256d tx = neg(ny);  // t = perp(n) = (-ny, nx)
        __m256d vxi, vyi, vxj, vyj;
        load_xy(vel, i0, i1, i2, i3, vxi, vyi);
        load_xy(vel, j0, j1, j2, j3, vxj, vyj);
        const __m256d vrx = _mm256_sub_pd(vxj, vxi), vry = _mm256_sub_pd(vyj, vyi);
        const __m256d wi = load4(d.omega, i0, i1, i2, i3), wj = load4(d.omega, j0, j1, j2, j3);
        const __m256d vn = _mm256_add_pd(_mm256_mul_pd(vrx, nx), _mm256_mul_pd(vry, ny));
        const __m256d vt = _mm256_add_pd(_mm256_mul_pd(vrx, tx), _mm256_mul_pd(vry, nx));
        const __m256d half_overlap = _mm256_mul_pd(half, overlap);
        const __m256d ra = _mm256_sub_pd(ri, half_overlap), rb = _mm256_sub_pd(rj, half_overlap);
        const __m256d vs = _mm256_sub_pd(vt, _mm256_add_pd(_mm256_mul_pd(wi, ra), _mm256_mul_pd(wj, rb)));

        // the contacts' histories and the pairs' materials
        // (one material, as in the flume and DB-9k: the same lanes for every group)
        const PairLanes pl = kOneMaterial ? one : pair_lanes(p, d, i0, i1, i2, i3, j0, j1, j2, j3);
        const __m256d kn = pl.kn, ks = pl.ks, mu = pl.mu, inv_ks = pl.inv_ks;
        const __m256d cn = _mm256_set_pd(q[3]->cn, q[2]->cn, q[1]->cn, q[0]->cn);
        const __m256d cs = _mm256_set_pd(q[3]->cs, q[2]->cs, q[1]->cs, q[0]->cs);
        const __m256d fs_old = _mm256_set_pd(q[3]->fs, q[2]->fs, q[1]->fs, q[0]->fs);
        const __m256d damp_n_old = _mm256_cvtps_pd(_mm_set_ps(q[3]->damp_n, q[2]->damp_n, q[1]->damp_n, q[0]->damp_n));
        const __m256d damp_s_old = _mm256_cvtps_pd(_mm_set_ps(q[3]->damp_s, q[2]->damp_s, q[1]->damp_s, q[0]->damp_s));

        // linear_contact (contact_law.h), operation for operation
        const __m256d fn_spring = _mm256_mul_pd(kn, overlap);
        const __m256d damp_n_free = _mm256_mul_pd(neg(cn), vn);
        const __m256d fn_free = _mm256_add_pd(fn_spring, damp_n_free);
        const __m256d cut_tension = _mm256_and_pd(no_tension_m, _mm256_cmp_pd(fn_free, zero, _CMP_LT_OQ));
        const __m256d fn = blend(cut_tension, zero, fn_free);
        const __m256d fn_damp = blend(cut_tension, neg(fn_spring), damp_n_free);
        const __m256d fs_trial = _mm256_sub_pd(fs_old, _mm256_mul_pd(_mm256_mul_pd(ks, vs), dt));
        const __m256d fs_max = _mm256_mul_pd(mu, fn_spring);
        const __m256d excess = _mm256_sub_pd(_mm256_andnot_pd(_mm256_set1_pd(-0.0), fs_trial), fs_max);
        const __m256d sliding = _mm256_cmp_pd(excess, zero, _CMP_GT_OQ);
        const __m256d fs = _mm256_min_pd(fs_max, _mm256_max_pd(neg(fs_max), fs_trial));
        const __m256d slip_work = _mm256_mul_pd(_mm256_mul_pd(fs_max, _mm256_max_pd(zero, excess)), inv_ks);
        const __m256d fs_damp = blend(_mm256_and_pd(sliding, no_shear_sliding_m), zero, _mm256_mul_pd(neg(cs), vs));
        const __m256d ft = _mm256_add_pd(fs, fs_damp);
        // LinearLaw::step: the dashpots' work centred on v(t - dt/2)
        const __m256d work_n = _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(fn_damp, dt), _mm256_mul_pd(damp_n_old, last_dt)), vn);
        const __m256d work_s = _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(fs_damp, dt), _mm256_mul_pd(damp_s_old, last_dt)), vs);
        const __m256d diss_touching = _mm256_sub_pd(slip_work, _mm256_mul_pd(half, _mm256_add_pd(work_n, work_s)));

        // an open pair: the last dashpot forces' second half, with the radii as lever arms
        const __m256d vs_open = _mm256_sub_pd(vt, _mm256_add_pd(_mm256_mul_pd(wi, ri), _mm256_mul_pd(wj, rj)));
        const __m256d had_dashpots =
            _mm256_or_pd(_mm256_cmp_pd(damp_n_old, zero, _CMP_NEQ_UQ), _mm256_cmp_pd(damp_s_old, zero, _CMP_NEQ_UQ));
        const __m256d diss_open = _mm256_and_pd(
            had_dashpots, _mm256_mul_pd(minus_half_last_dt,
                                        _mm256_add_pd(_mm256_mul_pd(damp_n_old, vn), _mm256_mul_pd(damp_s_old, vs_open))));

        // results: force on j = fn n + ft t; torques -r ft; +0 for an open pair (PairBatch),
        // as a record per pair and disc (the lanes transposed)
        const __m256d fx = _mm256_and_pd(touching, _mm256_add_pd(_mm256_mul_pd(fn, nx), _mm256_mul_pd(ft, tx)));
        const __m256d fy = _mm256_and_pd(touching, _mm256_add_pd(_mm256_mul_pd(fn, ny), _mm256_mul_pd(ft, nx)));
        const __m256d torque_i = _mm256_and_pd(touching, _mm256_mul_pd(neg(ra), ft));
        const __m256d torque_j = _mm256_and_pd(touching, _mm256_mul_pd(neg(rb), ft));
        const __m256d k_tran_t = _mm256_and_pd(touching, pl.k_tran);
        store_rows(out.to_i + g, neg(fx), neg(fy), torque_i, k_tran_t);
        store_rows(out.to_j + g, fx, fy, torque_j, k_tran_t);
        const __m256d k_rot = _mm256_and_pd(touching, ks);
        const __m256d half_dissipated = _mm256_mul_pd(half, blend(touching, diss_touching, diss_open));
        const __m256d lo = _mm256_unpacklo_pd(k_rot, half_dissipated);  // pairs 0 and 2
        const __m256d hi = _mm256_unpackhi_pd(k_rot, half_dissipated);  // pairs 1 and 3
        _mm_store_pd(out.to_both[g], _mm256_castpd256_pd128(lo));
        _mm_store_pd(out.to_both[g + 1], _mm256_castpd256_pd128(hi));
        _mm_store_pd(out.to_both[g + 2], _mm256_extractf128_pd(lo, 1));
        _mm_store_pd(out.to_both[g + 3], _mm256_extractf128_pd(hi, 1));
        // the mask's lanes (all ones) as 32-bit integers, negated: 1 or 0
        _mm_store_si128(reinterpret_cast<__m128i*>(out.touching + g),
                        _mm_sub_epi32(_mm_setzero_si128(), _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(
                                                               _mm256_castpd_si256(touching), _mm256_setr_epi32(0, 2, 4, 6, 0, 0, 0, 0)))));
        // the histories: an open pair starts again from zero (PFC deletes it)
        alignas(32) double fs_new[4];
        alignas(16) float dn_new[4], ds_new[4];
        _mm256_store_pd(fs_new, _mm256_and_pd(touching, fs));
        _mm_store_ps(dn_new, _mm256_cvtpd_ps(_mm256_and_pd(touching, fn_damp)));
        _mm_store_ps(ds_new, _mm256_cvtpd_ps(_mm256_and_pd(touching, fs_damp)));
        for (int l = 0; l < 4; ++l) {
            q[l]->fs = fs_new[l];
            q[l]->damp_n = dn_new[l];
            q[l]->damp_s = ds_new[l];
        }
        // the clearance test: a touching pair is to do next step without a look (-1); an open
        // one, with the zero history just written, is looked at (0)
        if (skip) {
            alignas(16) float v[4];
            _mm_store_ps(v, _mm256_cvtpd_ps(_mm256_and_pd(touching, _mm256_set1_pd(-1.0))));
            for (int l = 0; l < 4; ++l) skip->clearance[out.index[g + l]] = v[l];
        }
    }
    return m;
}

template <bool kOneMaterial>
DEMLAB_AVX2 size_t disc_pairs(const DiscArrays& d, const PairPassParams& p, DiscContact* c, size_t n, PairBatch& out,
                              const PairSkip* skip) {
    const size_t covered = pair_select::select_pairs(d, c, n, out, skip, 4);
    const size_t m = out.count;
    const size_t done = law<kOneMaterial>(d, p, c, out, skip);
    return done < m ? out.index[done] : covered;
}

}  // namespace

// The sums of the scalar pass (add_to_i, add_to_j in force_pass.cpp) for a record at a time: the
// same additions, lane by lane, in the same order of pairs.
[[gnu::target("avx2")]] void add_pair_batch_avx2(const PairBatch& batch, const DiscContact* c, DiscLoad* load) {
    static_assert(offsetof(DiscLoad, force) == 0 && offsetof(DiscLoad, torque) == 16 && offsetof(DiscLoad, k_tran) == 24 &&
                  offsetof(DiscLoad, k_rot) == 32 && offsetof(DiscLoad, dissipated) == 40);
    for (size_t b = 0, n = batch.count; b < n; ++b) {
        // everything read from the batch and the contact first: the stores into the loads
        // may alias them as far as the compiler knows, and it reloaded i, j and the touching
        // flag after each (a third of the loop's instructions)
        const DiscContact& cb = c[batch.index[b]];
        const size_t i = size_t(cb.i), j = size_t(cb.j);
        const int32_t touching = batch.touching[b];
        const __m128d both = _mm_load_pd(batch.to_both[b]);
        const __m256d to_i = _mm256_load_pd(batch.to_i[b]), to_j = _mm256_load_pd(batch.to_j[b]);
        double* const li = reinterpret_cast<double*>(load + i);
        _mm256_store_pd(li, _mm256_add_pd(_mm256_load_pd(li), to_i));
        _mm_store_pd(li + 4, _mm_add_pd(_mm_load_pd(li + 4), both));
        load[i].n_disc += touching;
        double* const lj = reinterpret_cast<double*>(load + j);
        _mm256_store_pd(lj, _mm256_add_pd(_mm256_load_pd(lj), to_j));
        _mm_store_pd(lj + 4, _mm_add_pd(_mm_load_pd(lj + 4), both));
        load[j].n_disc += touching;
    }
}

[[gnu::target("avx2")]] size_t disc_pairs_avx2(const DiscArrays& d, const PairPassParams& p, DiscContact* c, size_t n,
                                               PairBatch& out, const PairSkip* skip) {
    return p.n_materials == 1 ? disc_pairs<true>(d, p, c, n, out, skip) : disc_pairs<false>(d, p, c, n, out, skip);
}

[[gnu::target("avx2")]] size_t pair_law_avx2(const DiscArrays& d, const PairPassParams& p, DiscContact* c, PairBatch& out) {
    const size_t m = out.count;
    if (m == 0) return 0;
    for (size_t l = m; l % 4 != 0; ++l) out.index[l] = out.index[m - 1];  // padding: the last pair again
    return p.n_materials == 1 ? law<true>(d, p, c, out, nullptr) : law<false>(d, p, c, out, nullptr);
}
#else
size_t pair_law_avx2(const DiscArrays&, const PairPassParams&, DiscContact*, PairBatch&) { return 0; }
size_t disc_pairs_avx2(const DiscArrays&, const PairPassParams&, DiscContact*, size_t, PairBatch&, const PairSkip*) {
    return 0;
}
void add_pair_batch_avx2(const PairBatch&, const DiscContact*, DiscLoad*) {}
#endif

}  // namespace demlab
