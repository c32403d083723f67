// The centred dashpots' shifts for a list of touching pairs, written once over the lanes of
// dem/lanes/ and compiled for each width by its own file (centre_avx2.cpp: four pairs a time,
// centre_avx512.cpp: eight). The includer defines DEMLAB_WIDE_TARGET first.
//
// Why: gathering each pair's inputs one value at a time into a CentreBlock's arrays (25 loads
// and stores a pair, centred_dashpots.cpp's scalar gather) was two thirds of the centre pass
// and about a sixth of a flume step. Here the two discs' records (eight doubles each,
// CentreDisc) come in as whole rows and are transposed into lanes, the positions as pairs, and
// the arithmetic runs in the same registers; only the outputs go through the block, which the
// caller adds into the discs in list order as before.
//
// Same bits as centre_lanes.h (and so as the scalar formulas): every lane does its operations
// in its order, with the same operands (the differences v_j - v_i, 1/m_i + 1/m_j and the
// distance are formed as the scalar gather forms them); the modes' conditions are selects on
// the same comparisons; no FMA (the files are compiled with -ffp-contract=off).
#pragma once
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "dem/centre_lanes.h"
#include "dem/lanes/wide_target.h"

namespace demlab {
namespace centre_wide {

template <typename W, bool kOneMaterial>
DEMLAB_WIDE bool touching(const CentrePairArrays& a, const uint32_t* list, size_t n, CentreBlock& b, const CentreConsts& k) {
    using D = typename W::D;
    using M = typename W::M;
    constexpr size_t N = W::kWidth;
    const D dt = W::set1(k.dt), h = W::set1(k.half_dt);
    const D half = W::set1(0.5), one = W::set1(1.0), zero = W::zero();
    const M rotation_free = W::mask(k.rotation_free), no_tension = W::mask(k.no_tension),
            no_shear_sliding = W::mask(k.no_shear_sliding);
    const D kn_one = kOneMaterial ? W::set1(a.materials[0].kn) : zero;
    const D mu_one = kOneMaterial ? W::set1(a.materials[0].mu) : zero;
    for (size_t g = 0; g < n; g += N) {
        // the records of the group two ahead asked for now, when the step's arrays outgrow the
        // cache (the force pass' switch): at the real sand size (145,615 discs, 9.3 MB of
        // records) disc j's row came from memory, and waiting for it was most of this pass
        if (a.prefetch) {
            // and the contacts of the group four ahead, whose j the lines below read: found
            // from the list only when their turn came, they were the next wait (a contact is
            // 40 bytes, so its last byte may lie on the next line)
            for (size_t l = 4 * N; l < 5 * N && g + l < n; ++l) {
                const char* c = reinterpret_cast<const char*>(a.contacts + list[g + l]);
                __builtin_prefetch(c);
                __builtin_prefetch(c + sizeof(DiscContact) - 1);
            }
            for (size_t l = 2 * N; l < 3 * N && g + l < n; ++l) {
                const DiscContact& ahead = a.contacts[list[g + l]];
                __builtin_prefetch(a.discs + 8 * size_t(ahead.j));
                __builtin_prefetch(a.pos + 2 * size_t(ahead.j));
            }
        }
        // the lanes past n repeat the last pair (computed, not added)
        const DiscContact* q[N];
        size_t i[N], j[N];
        const double* rows_i[N];
        const double* rows_j[N];
        for (size_t l = 0; l < N; ++l) {
            q[l] = a.contacts + list[std::min(g + l, n - 1)];
            i[l] = size_t(q[l]->i);
            j[l] = size_t(q[l]->j);
            rows_i[l] = a.discs + 8 * i[l];
            rows_j[l] = a.discs + 8 * j[l];
        }
        D xi, yi, xj, yj;
        W::load_xy_at(a.pos, i, xi, yi);
        W::load_xy_at(a.pos, j, xj, yj);
        const D ri = W::gather([&](size_t l) { return a.radius[i[l]]; });
        const D rj = W::gather([&](size_t l) { return a.radius[j[l]]; });
        const D dx = xj - xi, dy = yj - yi;
        const D dist2 = dx * dx + dy * dy;
        const D rsum = ri + rj;
        // the scalar gather's test (dist2 >= rsum^2: left out)
        if (any(cmp<_CMP_GE_OQ>(dist2, rsum * rsum))) {
            b.count = 0;
            return false;
        }
        // the records: vx, vy, w, pvx, pvy, pw, inv_mass, inv_inertia
        D di[8], dj[8];
        W::transpose_records(rows_i, di);
        W::transpose_records(rows_j, dj);
        const D vrx = dj[0] - di[0], vry = dj[1] - di[1];
        const D wi = di[2], wj = dj[2];
        const D prx = dj[3] - di[3], pry = dj[4] - di[4];
        const D pwi = di[5], pwj = dj[5];
        const D inv_mn = di[6] + dj[6];
        const D inv_ii = di[7], inv_ij = dj[7];
        D kn = kn_one, mu = mu_one;
        if constexpr (!kOneMaterial) {
            const PairMaterial* pm[N];
            for (size_t l = 0; l < N; ++l)
                pm[l] = &a.materials[size_t(a.material[i[l]]) * a.n_materials + size_t(a.material[j[l]])];
            kn = W::gather([&](size_t l) { return pm[l]->kn; });
            mu = W::gather([&](size_t l) { return pm[l]->mu; });
        }
        const D cn = W::gather([&](size_t l) { return q[l]->cn; });
        const D cs = W::gather([&](size_t l) { return q[l]->cs; });
        const D fs = W::gather([&](size_t l) { return q[l]->fs; });

        // centre_lanes, operation for operation
        const D dist = sqrt(dist2);
        const D overlap = rsum - dist;
        const D nx = dx / dist, ny = dy / dist;
        const D tx = -ny, ty = nx;
        const D ra = ri - half * overlap, rb = rj - half * overlap;
        const D vn = vrx * nx + vry * ny;
        const D vs = (vrx * tx + vry * ty) - (wi * ra + wj * rb);
        const D pn = prx * nx + pry * ny;
        const D ps = (prx * tx + pry * ty) - (pwi * ra + pwj * rb);
        const D inv_ms = select(rotation_free, inv_mn + ra * ra * inv_ii + rb * rb * inv_ij, inv_mn);
        const D fn_spring = kn * overlap;
        // normal: u(t) = (u* + (g/2) u-) / (1 + g/2), g = c dt / m; no tension: std::max(d, -fn_spring)
        const D gn = cn * dt * inv_mn;
        D dn_old = -cn * vn;
        D dn_new = -cn * ((pn + half * gn * vn) / (one + half * gn));
        const D cap = -fn_spring;
        dn_old = select(no_tension & cmp<_CMP_LT_OQ>(dn_old, cap), cap, dn_old);
        dn_new = select(no_tension & cmp<_CMP_LT_OQ>(dn_new, cap), cap, dn_new);
        // shear: none while the contact slides
        const D gs = cs * dt * inv_ms;
        D ds_old = -cs * vs;
        D ds_new = -cs * ((ps + half * gs * vs) / (one + half * gs));
        const M sliding = no_shear_sliding & cmp<_CMP_GE_OQ>(abs(fs), mu * fn_spring);
        ds_old = select(sliding, zero, ds_old);
        ds_new = select(sliding, zero, ds_new);
        const D dn = dn_new - dn_old, ds = ds_new - ds_old;
        W::store(b.fx + g, dn * nx + ds * tx);
        W::store(b.fy + g, dn * ny + ds * ty);
        W::store(b.torque_i + g, -ra * ds);
        W::store(b.torque_j + g, -rb * ds);
        W::store(b.dissipated + g, -h * (dn * vn + ds * vs));
        W::store(b.damp_n + g, dn_new);
        W::store(b.damp_s + g, ds_new);
        for (size_t l = 0, m = std::min(N, n - g); l < m; ++l) {
            b.contact[g + l] = list[g + l];
            b.i[g + l] = int32_t(i[l]);
            b.j[g + l] = int32_t(j[l]);
        }
    }
    b.count = n;
    return true;
}

template <typename W>
DEMLAB_WIDE bool touching_any(const CentrePairArrays& a, const uint32_t* list, size_t n, CentreBlock& b, const CentreConsts& k) {
    return a.n_materials == 1 ? touching<W, true>(a, list, n, b, k) : touching<W, false>(a, list, n, b, k);
}

}  // namespace centre_wide
}  // namespace demlab
#endif
