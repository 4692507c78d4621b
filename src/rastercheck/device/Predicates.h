#pragma once

// Exact orientation predicates on doubles, for the exact phase on both backends (the triangle tests
// of device/TriangleTests.h). A floating-point filter decides almost every call; the rest are
// evaluated exactly with floating-point expansions after J. R. Shewchuk, "Adaptive Precision
// Floating-Point Arithmetic and Fast Robust Geometric Predicates" (1997): a value is held exactly as
// a sum of non-overlapping doubles of increasing magnitude, so its sign is the sign of the last
// (largest) term. Only the rare calls the filter cannot decide come there, so that part favours
// clarity over speed; the capacity covers the largest intermediate of orient3d (3 terms of 64
// components). Exact only where every operation rounds once: nvcc builds with --fmad=false (no
// contraction into fused multiply-adds) and twoProduct's fma is the one fused operation meant.

#include <cmath>

#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"

namespace rastercheck::device
{
namespace predicates
{
constexpr double kEpsilon = 0x1p-53;  // half an ulp of 1: the relative rounding error of one operation
constexpr double kOrient2dBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;
constexpr double kOrient3dBound = (7.0 + 56.0 * kEpsilon) * kEpsilon;

template <int Capacity>
struct Expansion
{
    double term[Capacity];
    int size = 0;
};

RC_HD void twoSum(double a, double b, double &sum, double &error)
{
    sum = a + b;
    const double bVirtual = sum - a;
    const double aVirtual = sum - bVirtual;
    error = (a - aVirtual) + (b - bVirtual);
}

RC_HD void fastTwoSum(double a, double b, double &sum, double &error)
{
    sum = a + b;
    error = b - (sum - a);
}

RC_HD void twoProduct(double a, double b, double &product, double &error)
{
    product = a * b;
    error = fma(a, b, -product);  // exact: fma rounds once, and a*b - product is representable
}

RC_HD Expansion<2> exactDifference(double a, double b)
{
    Expansion<2> e;
    double sum = 0.0, error = 0.0;
    twoSum(a, -b, sum, error);
    if (error != 0.0)
        e.term[e.size++] = error;
    e.term[e.size++] = sum;
    return e;
}

// h = e + b (Shewchuk's GROW-EXPANSION with zero elimination).
// The caller guarantees room for e.size + 1 terms.
template <int Out, int In>
RC_HD void growExpansion(const Expansion<In> &e, double b, Expansion<Out> &h)
{
    double q = b;
    h.size = 0;
    for (int i = 0; i < e.size; ++i)
    {
        double sum = 0.0, error = 0.0;
        twoSum(q, e.term[i], sum, error);
        q = sum;
        if (error != 0.0)
            h.term[h.size++] = error;
    }
    if (q != 0.0 || h.size == 0)
        h.term[h.size++] = q;
}

template <int Out, int In>
RC_HD void copyExpansion(const Expansion<In> &e, Expansion<Out> &h)
{
    h.size = e.size;
    for (int i = 0; i < e.size; ++i)
        h.term[i] = e.term[i];
}

// h = e + f, by growing e with each term of f (the result stays non-overlapping). The caller
// guarantees room for e.size + f.size terms.
template <int Out, int InE, int InF>
RC_HD void sumExpansions(const Expansion<InE> &e, const Expansion<InF> &f, Expansion<Out> &h)
{
    Expansion<Out> scratch;
    copyExpansion(e, h);
    for (int j = 0; j < f.size; ++j)
    {
        growExpansion(h, f.term[j], scratch);
        copyExpansion(scratch, h);
    }
}

// h = e * b (Shewchuk's SCALE-EXPANSION with zero elimination).
template <int Out, int In>
RC_HD void scaleExpansion(const Expansion<In> &e, double b, Expansion<Out> &h)
{
    static_assert(Out >= 2 * In, "expansion capacity");
    h.size = 0;
    double q = 0.0, error = 0.0;
    twoProduct(e.term[0], b, q, error);
    if (error != 0.0)
        h.term[h.size++] = error;
    for (int i = 1; i < e.size; ++i)
    {
        double high = 0.0, low = 0.0, sum = 0.0;
        twoProduct(e.term[i], b, high, low);
        twoSum(q, low, sum, error);
        if (error != 0.0)
            h.term[h.size++] = error;
        fastTwoSum(high, sum, q, error);
        if (error != 0.0)
            h.term[h.size++] = error;
    }
    if (q != 0.0 || h.size == 0)
        h.term[h.size++] = q;
}

template <int Out, int InE, int InF>
RC_HD void multiplyExpansions(const Expansion<InE> &e, const Expansion<InF> &f, Expansion<Out> &h)
{
    static_assert(Out >= 2 * InE * InF, "expansion capacity");
    h.size = 1;
    h.term[0] = 0.0;
    Expansion<2 * InE> partial;
    Expansion<Out> scratch;
    for (int j = 0; j < f.size; ++j)
    {
        scaleExpansion(e, f.term[j], partial);
        sumExpansions(h, partial, scratch);
        copyExpansion(scratch, h);
    }
}

template <int Capacity>
RC_HD Expansion<Capacity> negated(Expansion<Capacity> e)
{
    for (int i = 0; i < e.size; ++i)
        e.term[i] = -e.term[i];
    return e;
}

template <int Capacity>
RC_HD int sign(const Expansion<Capacity> &e)
{
    const double top = e.term[e.size - 1];
    return (top > 0.0) - (top < 0.0);
}

// e1 * f1 - e2 * f2 for two-term factors.
RC_HD Expansion<16> exactMinor(const Expansion<2> &e1, const Expansion<2> &f1, const Expansion<2> &e2,
                               const Expansion<2> &f2)
{
    Expansion<8> left, right;
    multiplyExpansions(e1, f1, left);
    multiplyExpansions(e2, f2, right);
    Expansion<16> minor;
    sumExpansions(left, negated(right), minor);
    return minor;
}

RC_HD_CALL int orient2dExact(double ax, double ay, double bx, double by, double cx, double cy)
{
    const Expansion<16> det =
        exactMinor(exactDifference(bx, ax), exactDifference(cy, ay), exactDifference(by, ay), exactDifference(cx, ax));
    return sign(det);
}

RC_HD_CALL int orient3dExact(const Vec3<double> &a, const Vec3<double> &b, const Vec3<double> &c, const Vec3<double> &d)
{
    // ((b - a) x (c - a)) . (d - a) as a cofactor expansion along d - a.
    Expansion<2> u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k)
    {
        u[k] = exactDifference(b[k], a[k]);
        v[k] = exactDifference(c[k], a[k]);
        w[k] = exactDifference(d[k], a[k]);
    }
    Expansion<64> terms[3];
    for (int k = 0; k < 3; ++k)
    {
        const int i = (k + 1) % 3, j = (k + 2) % 3;
        multiplyExpansions(exactMinor(u[i], v[j], u[j], v[i]), w[k], terms[k]);
    }
    Expansion<128> partial;
    sumExpansions(terms[0], terms[1], partial);
    Expansion<192> det;
    sumExpansions(partial, terms[2], det);
    return sign(det);
}
}  // namespace predicates

/** \brief Exact sign of (b - a) x (c - a) in the plane: positive when a, b, c turn counter-clockwise,
    0 when collinear (exactly, for the double coordinates given). */
RC_HD int orient2d(double ax, double ay, double bx, double by, double cx, double cy)
{
    const double left = (bx - ax) * (cy - ay);
    const double right = (by - ay) * (cx - ax);
    const double det = left - right;
    const double bound = predicates::kOrient2dBound * (std::fabs(left) + std::fabs(right));
    if (det > bound)
        return 1;
    if (-det > bound)
        return -1;
    return predicates::orient2dExact(ax, ay, bx, by, cx, cy);
}

/** \brief Exact sign of the orientation of \a d against the plane through \a a, \a b, \a c: sign of
    ((b - a) x (c - a)) . (d - a). Positive when \a d lies on the side the normal of the
    counter-clockwise triangle abc points to, 0 when the four points are coplanar (exactly, for the
    double coordinates given), barring overflow or underflow of the products. */
RC_HD int orient3d(const Vec3<double> &a, const Vec3<double> &b, const Vec3<double> &c, const Vec3<double> &d)
{
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
    const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    const double wx = d.x - a.x, wy = d.y - a.y, wz = d.z - a.z;
    const double uyvz = uy * vz, uzvy = uz * vy;
    const double uzvx = uz * vx, uxvz = ux * vz;
    const double uxvy = ux * vy, uyvx = uy * vx;
    const double det = wx * (uyvz - uzvy) + wy * (uzvx - uxvz) + wz * (uxvy - uyvx);
    const double permanent = std::fabs(wx) * (std::fabs(uyvz) + std::fabs(uzvy)) +
                             std::fabs(wy) * (std::fabs(uzvx) + std::fabs(uxvz)) +
                             std::fabs(wz) * (std::fabs(uxvy) + std::fabs(uyvx));
    const double bound = predicates::kOrient3dBound * permanent;
    if (det > bound)
        return 1;
    if (-det > bound)
        return -1;
    return predicates::orient3dExact(a, b, c, d);
}
}  // namespace rastercheck::device
