// judge.hpp -- a library result against the long-double reference tracer
// (reference.hpp) for the same prepared ray: the verdict test_trace and
// test_tiles count.  A result agrees when status and position agree (the
// position within POS_TOL_Q16 per axis); a disagreement is a tangency when
// the ray comes within EPS_LSB of the surface where the two disagree (the
// reference's own rounding, checked analytically by ref::min_clearance);
// anything else is a wrong-surface result.
#pragma once

#include <algorithm>
#include <cmath>

#include "conetrace.h"
#include "reference.hpp"

namespace judge {

constexpr double POS_TOL_Q16 = 2.5;  // stated bound: 2 Q16 units per axis (+ reference slack)
constexpr double EPS_LSB = 1e-6;     // tangency band for disputes

inline ref::Ray to_ref(const ct_prepared &p)
{
    ref::Ray r;
    r.ox = (ref::ld)p.ox / 65536;
    r.oy = (ref::ld)p.oy / 65536;
    r.oz = std::ldexp((ref::ld)p.oz, p.zshift) / 65536;  // z in units of 2^zshift Q16
    r.dx = (ref::ld)p.dx / 65536;
    r.dy = (ref::ld)p.dy / 65536;
    r.dz = std::ldexp((ref::ld)p.dz, p.zshift) / 65536;
    r.tend = (ref::ld)p.tend_n / (ref::ld)p.tend_d;
    return r;
}

// Classify a disagreement; returns true when it is a tangency.
inline bool tangent_ok(const ref::Dem &d, const ref::Ray &r, int ls, ref::ld tl, const ref::Hit &rh)
{
    const ref::ld e = EPS_LSB, dt = 1.0L / (1 << 25);
    bool lhit = ls == CT_HIT || ls == CT_HIT_VOID;
    if (ls == CT_BELOW || rh.status == ref::BELOW) {
        return std::fabs((double)(r.oz - ref::surface(d, r.ox, r.oy))) <= EPS_LSB;
    }
    if (lhit && (rh.status != ref::HIT || tl < rh.t)) {
        // the library stops earlier: it must be touching there
        return ref::min_clearance(d, r, tl, tl + dt) <= e;
    }
    if (rh.status == ref::HIT && (!lhit || tl > rh.t)) {
        // the library goes on past the reference's hit: that hit must be a graze
        ref::ld upto = lhit ? tl : r.tend;
        return ref::min_clearance(d, r, rh.t - dt, upto) >= -e;
    }
    return false;
}

enum Verdict { AGREE, TANGENT, WRONG };

// s, h: the library's result for prepared ray pr on DEM d.  *rh: the
// reference's; *err: the position error (Q16, max over axes) of an
// agreeing hit (else untouched).
inline Verdict judge(const ref::Dem &d, const ct_prepared &pr, ct_status s, const ct_hit &h, ref::Hit *rh,
                     double *err)
{
    const ref::Ray rr = to_ref(pr);
    *rh = ref::trace(d, rr);
    const bool lhit = s == CT_HIT || s == CT_HIT_VOID;
    bool agree;
    if (lhit && rh->status == ref::HIT) {
        double ex = std::fabs((double)(h.x_q16 - rh->x * 65536));
        double ey = std::fabs((double)(h.y_q16 - rh->y * 65536));
        double ez = std::fabs((double)(h.z_q16 - rh->z * 65536));
        double e = std::max(ex, std::max(ey, ez));
        agree = e <= POS_TOL_Q16;
        if (agree) *err = e;
    } else {
        agree = (s == CT_MISS && rh->status == ref::MISS) || (s == CT_BELOW && rh->status == ref::BELOW);
    }
    if (agree) return AGREE;
    return tangent_ok(d, rr, s, (ref::ld)h.t_q26 / (1 << 26), *rh) ? TANGENT : WRONG;
}

}  // namespace judge
