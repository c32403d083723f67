// The disc-disc law of pair_kernel.h a group of pairs at a time, written once over the lanes of
// dem/lanes/ and compiled for each width by its own file: four pairs in AVX2 registers
// (pair_kernel_avx2.cpp, lane set lanes::Avx2) and eight in AVX-512 ones
// (pair_kernel_avx512.cpp, lanes::Avx512). The includer defines DEMLAB_WIDE_TARGET, the target
// its functions are compiled for, before it includes this (lanes/wide_target.h); the selection
// stages before the law are the AVX2 ones for both widths (pair_select_avx2.h), and the results
// go into one PairBatch.
//
// Same bits as disc_pair_force: every lane does the scalar kernel's operations in the scalar
// kernel's order, and IEEE addition, multiplication, division and square root are correctly
// rounded whatever the register width. Three things keep it so:
// - No FMA (lanes_avx2.h): "avx2" does not include it, and the AVX-512 file is compiled with
//   -ffp-contract=off (CMakeLists.txt); GCC's default -ffp-contract=fast would contract
//   a * b + c into one rounding, and the bits would differ.
// - min/max in the order of std::min/std::max: std::max(a, b) is (a < b) ? b : a, which is
//   max(b, a) of the lanes (the instruction returns its second operand unless the first is
//   greater), so both agree on signed zeros and NaN.
// - The selects of contact_law.h become selects of lanes on the same conditions.
// The caller sums the batch's results into the discs in list order, as the scalar pass does
// (force_pass.cpp), so the sums are the same bits too.
#pragma once
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <cstddef>
#include <cstdint>

#include "dem/laws/pair_kernel.h"
#include "dem/laws/pair_select_avx2.h"
#include "dem/lanes/wide_target.h"

namespace demlab {
namespace pair_wide {

// A group's materials (PairMaterial) as lanes.
template <typename W>
struct PairLanes {
    typename W::D kn, ks, mu, inv_ks, k_tran;
};

template <typename W>
DEMLAB_WIDE PairLanes<W> broadcast_lanes(const PairMaterial& m) {
    return {W::set1(m.kn), W::set1(m.ks), W::set1(m.mu), W::set1(m.inv_ks), W::set1(m.k_tran)};
}

template <typename W>
DEMLAB_WIDE PairLanes<W> pair_lanes(const PairPassParams& p, const DiscArrays& d, const size_t* i, const size_t* j) {
    const PairMaterial* pm[W::kWidth];
    for (size_t l = 0; l < W::kWidth; ++l)
        pm[l] = &p.materials[size_t(d.material[i[l]]) * p.n_materials + size_t(d.material[j[l]])];
    return {W::gather([&](size_t l) { return pm[l]->kn; }), W::gather([&](size_t l) { return pm[l]->ks; }),
            W::gather([&](size_t l) { return pm[l]->mu; }), W::gather([&](size_t l) { return pm[l]->inv_ks; }),
            W::gather([&](size_t l) { return pm[l]->k_tran; })};
}

// The law for the contacts c + out.index[b], b < out.count (the list padded to a multiple of
// the width), results into out in that order. Returns how many it did: out.count, or fewer when
// a group holds a blown-up pair: then it stops before that group (out.count is cut there) and
// writes nothing from there on, for the scalar kernel to report. With skip, the clearances of
// the pairs it does are marked.
template <typename W, bool kOneMaterial>
DEMLAB_WIDE size_t law(const DiscArrays& d, const PairPassParams& p, DiscContact* c, PairBatch& out, const PairSkip* skip) {
    using D = typename W::D;
    using M = typename W::M;
    constexpr size_t N = W::kWidth;
    const PairLanes<W> one = kOneMaterial ? broadcast_lanes<W>(p.materials[0]) : PairLanes<W>{};
    const double* pos = d.pos->data();
    const double* vel = d.vel->data();
    const bool no_tension = p.mode == DashpotMode::NoTension || p.mode == DashpotMode::NoTensionNoShearWhileSliding;
    const bool no_shear_sliding =
        p.mode == DashpotMode::NoShearWhileSliding || p.mode == DashpotMode::NoTensionNoShearWhileSliding;
    const M no_tension_m = W::mask(no_tension), no_shear_sliding_m = W::mask(no_shear_sliding);
    const D zero = W::zero();
    const D half = W::set1(0.5);
    const D dt = W::set1(p.dt), last_dt = W::set1(p.last_dt);
    const D minus_half_last_dt = W::set1(-0.5 * p.last_dt);
    const D ratio = W::set1(p.max_overlap_ratio);
    const size_t m = out.count;

    for (size_t g = 0; g < m; g += N) {
        DiscContact* q[N];
        size_t i[N], j[N];
        for (size_t l = 0; l < N; ++l) {
            q[l] = c + out.index[g + l];
            i[l] = size_t(q[l]->i);
            j[l] = size_t(q[l]->j);
        }
        D xi, yi, xj, yj;
        W::load_xy_at(pos, i, xi, yi);
        W::load_xy_at(pos, j, xj, yj);
        const D ri = W::gather([&](size_t l) { return d.radius[i[l]]; });
        const D rj = W::gather([&](size_t l) { return d.radius[j[l]]; });
        const D dxx = xj - xi, dxy = yj - yi;
        const D rsum = ri + rj;
        const D dist2 = dxx * dxx + dxy * dxy;
        // the scalar kernel's "dist2 >= rsum^2: open" negated (NaN counts as touching, as there)
        const M touching = cmp<_CMP_NGE_UQ>(dist2, rsum * rsum);
        const D dist = sqrt(dist2);
        const D overlap = rsum - dist;
        const M fault = touching & (cmp<_CMP_NLE_UQ>(overlap, ratio * min(rj, ri)) | cmp<_CMP_EQ_OQ>(dist, zero));
        // A blown-up pair: leave this group untouched and stop before its first pair; the
        // pairs left out before that one had nothing to do. The caller's scalar kernel
        // reports it.
        if (any(fault)) {
            out.count = g;
            return g;
        }

        const D nx = dxx / dist, ny = dxy / dist;
        const D tx = -ny;  // t = perp(n) = (-ny, nx)
        D vxi, vyi, vxj, vyj;
        W::load_xy_at(vel, i, vxi, vyi);
        W::load_xy_at(vel, j, vxj, vyj);
        const D vrx = vxj - vxi, vry = vyj - vyi;
        const D wi = W::gather([&](size_t l) { return d.omega[i[l]]; });
        const D wj = W::gather([&](size_t l) { return d.omega[j[l]]; });
        const D vn = vrx * nx + vry * ny;
        const D vt = vrx * tx + vry * nx;
        const D half_overlap = half * overlap;
        const D ra = ri - half_overlap, rb = rj - half_overlap;
        const D vs = vt - (wi * ra + wj * rb);

        // the contacts' histories and the pairs' materials
        // (one material, as in the flume and DB-9k: the same lanes for every group)
        const PairLanes<W> pl = kOneMaterial ? one : pair_lanes<W>(p, d, i, j);
        const D kn = pl.kn, ks = pl.ks, mu = pl.mu, inv_ks = pl.inv_ks;
        const D cn = W::gather([&](size_t l) { return q[l]->cn; });
        const D cs = W::gather([&](size_t l) { return q[l]->cs; });
        const D fs_old = W::gather([&](size_t l) { return q[l]->fs; });
        const D damp_n_old = W::gather_float([&](size_t l) { return q[l]->damp_n; });
        const D damp_s_old = W::gather_float([&](size_t l) { return q[l]->damp_s; });

        // linear_contact (contact_law.h), operation for operation
        const D fn_spring = kn * overlap;
        const D damp_n_free = -cn * vn;
        const D fn_free = fn_spring + damp_n_free;
        const M cut_tension = no_tension_m & cmp<_CMP_LT_OQ>(fn_free, zero);
        const D fn = select(cut_tension, zero, fn_free);
        const D fn_damp = select(cut_tension, -fn_spring, damp_n_free);
        const D fs_trial = fs_old - ks * vs * dt;
        const D fs_max = mu * fn_spring;
        const D excess = abs(fs_trial) - fs_max;
        const M sliding = cmp<_CMP_GT_OQ>(excess, zero);
        const D fs = min(fs_max, max(-fs_max, fs_trial));
        const D slip_work = fs_max * max(zero, excess) * inv_ks;
        const D fs_damp = select(sliding & no_shear_sliding_m, zero, -cs * vs);
        const D ft = fs + fs_damp;
        // LinearLaw::step: the dashpots' work centred on v(t - dt/2)
        const D work_n = (fn_damp * dt + damp_n_old * last_dt) * vn;
        const D work_s = (fs_damp * dt + damp_s_old * last_dt) * vs;
        const D diss_touching = slip_work - half * (work_n + work_s);

        // an open pair: the last dashpot forces' second half, with the radii as lever arms
        const D vs_open = vt - (wi * ri + wj * rj);
        const M had_dashpots = cmp<_CMP_NEQ_UQ>(damp_n_old, zero) | cmp<_CMP_NEQ_UQ>(damp_s_old, zero);
        const D diss_open = keep(had_dashpots, minus_half_last_dt * (damp_n_old * vn + damp_s_old * vs_open));

        // results: force on j = fn n + ft t; torques -r ft; +0 for an open pair (PairBatch),
        // as a record per pair and disc (the lanes transposed)
        const D fx = keep(touching, fn * nx + ft * tx);
        const D fy = keep(touching, fn * ny + ft * nx);
        const D torque_i = keep(touching, -ra * ft);
        const D torque_j = keep(touching, -rb * ft);
        const D k_tran_t = keep(touching, pl.k_tran);
        W::store_rows(out.to_i + g, -fx, -fy, torque_i, k_tran_t);
        W::store_rows(out.to_j + g, fx, fy, torque_j, k_tran_t);
        W::store_pairs(out.to_both + g, keep(touching, ks), half * select(touching, diss_touching, diss_open));
        W::store_flags(out.touching + g, touching);
        // the histories: an open pair starts again from zero (PFC deletes it)
        alignas(64) double fs_new[N];
        alignas(32) float dn_new[N], ds_new[N];
        W::store(fs_new, keep(touching, fs));
        W::store_floats(dn_new, keep(touching, fn_damp));
        W::store_floats(ds_new, keep(touching, fs_damp));
        for (size_t l = 0; l < N; ++l) {
            q[l]->fs = fs_new[l];
            q[l]->damp_n = dn_new[l];
            q[l]->damp_s = ds_new[l];
        }
        // the clearance test: a touching pair is to do next step without a look (-1); an open
        // one, with the zero history just written, is looked at (0)
        if (skip) {
            alignas(32) float v[N];
            W::store_floats(v, keep(touching, W::set1(-1.0)));
            for (size_t l = 0; l < N; ++l) skip->clearance[out.index[g + l]] = v[l];
        }
    }
    return m;
}

// The pass over contacts c[0, n) (disc_pairs_avx2 in pair_kernel.h): the selection, then the law.
template <typename W, bool kOneMaterial>
DEMLAB_WIDE size_t disc_pairs(const DiscArrays& d, const PairPassParams& p, DiscContact* c, size_t n, PairBatch& out,
                              const PairSkip* skip) {
    const size_t covered = pair_select::select_pairs(d, c, n, out, skip, W::kWidth);
    const size_t m = out.count;
    const size_t done = law<W, kOneMaterial>(d, p, c, out, skip);
    return done < m ? out.index[done] : covered;
}

template <typename W>
DEMLAB_WIDE size_t disc_pairs_any(const DiscArrays& d, const PairPassParams& p, DiscContact* c, size_t n, PairBatch& out,
                                  const PairSkip* skip) {
    return p.n_materials == 1 ? disc_pairs<W, true>(d, p, c, n, out, skip) : disc_pairs<W, false>(d, p, c, n, out, skip);
}

// The law alone (pair_law_avx2 in pair_kernel.h): the list padded with its last pair.
template <typename W>
DEMLAB_WIDE size_t pair_law(const DiscArrays& d, const PairPassParams& p, DiscContact* c, PairBatch& out) {
    const size_t m = out.count;
    if (m == 0) return 0;
    for (size_t l = m; l % W::kWidth != 0; ++l) out.index[l] = out.index[m - 1];  // padding: the last pair again
    return p.n_materials == 1 ? law<W, true>(d, p, c, out, nullptr) : law<W, false>(d, p, c, out, nullptr);
}

}  // namespace pair_wide
}  // namespace demlab

#endif
