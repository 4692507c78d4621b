#pragma once

// Sine and cosine that round the same on the CPU and the GPU.
//
// Why not std::sin: glibc's and CUDA's double sine and cosine are both accurate to an ulp or two,
// but not the same ulp, so forward kinematics computed by the CUDA kernels would place a link a
// few ulps away from where the CPU backend places it, and a contact position, a pixel on a
// triangle's edge or a separation proof at its slack could differ between the two backends. This
// function uses only + - * / and rint, which IEEE 754 rounds the same everywhere (the CUDA build
// passes --fmad=false so nvcc does not fuse them, and the host build passes -ffp-contract=off): both
// backends get the same bits.
//
// The method is fdlibm's (Sun Microsystems, 1993; as in FreeBSD's msun and musl): a three-part
// Cody-Waite reduction by pi/2, exact for |x| < 2^20 * pi/2, and fdlibm's minimax polynomials on
// [-pi/4, pi/4], each within one ulp of the true value.

#include <cmath>

#include "rastercheck/device/HostDevice.h"

namespace rastercheck::device
{
namespace sincos_detail
{
/** \brief sin(x + y) for |x + y| <= pi/4, y the tail of a reduced argument. */
RC_HD double sineKernel(double x, double y)
{
    constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                     S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                     S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
    const double z = x * x, w = z * z;
    const double r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    const double v = z * x;
    return x - ((z * (0.5 * y - v * r) - y) - v * S1);
}

/** \brief cos(x + y) for |x + y| <= pi/4. */
RC_HD double cosineKernel(double x, double y)
{
    constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                     C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                     C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
    const double z = x * x, w = z * z;
    const double r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    const double hz = 0.5 * z, v = 1.0 - hz;
    return v + (((1.0 - v) - hz) + (z * r - x * y));
}
}  // namespace sincos_detail

/** \brief Largest |angle| that sinCos reduces exactly; beyond it the angle is first taken modulo
    the double nearest 2 pi (still the same bits on both backends, but off by |angle| * 2.4e-16). */
constexpr double kSinCosExactRange = 1.6e6;

/** \brief sin(angle) and cos(angle), identical on the CPU and the GPU, within one ulp of the true
    values for |angle| <= kSinCosExactRange. NaN and infinite angles give NaN. */
RC_HD void sinCos(double angle, double &sine, double &cosine)
{
    constexpr double kInvPio2 = 6.36619772367581382433e-01;
    // pi/2 in three 33-bit pieces (and their tails): n * piece is exact for |n| < 2^20.
    constexpr double kPio2_1 = 1.57079632673412561417e+00;
    constexpr double kPio2_2 = 6.07710050630396597660e-11, kPio2_2t = 2.02226624879595063154e-21;
    constexpr double kPio2_3 = 2.02226624871116645580e-21, kPio2_3t = 8.47842766036889956997e-32;
    constexpr double kTwoPi = 6.28318530717958647692;

    double x = angle;
    if (!(std::fabs(x) <= kSinCosExactRange))
    {
        if (!std::isfinite(x))
        {
            sine = cosine = x - x;  // NaN
            return;
        }
        x = std::fmod(x, kTwoPi);  // fmod is exact
    }
    // x - n pi/2 in double-double (head y0, tail y1), fdlibm's three rounds done unconditionally.
    const double n = std::rint(x * kInvPio2);
    // pi/2 = kPio2_1 + kPio2_2 + kPio2_3 + kPio2_3t; each round carries the previous one's rounding error.
    double r = x - n * kPio2_1;
    double t = r;
    double w = n * kPio2_2;
    r = t - w;
    w = n * kPio2_2t - ((t - r) - w);
    t = r;
    w = n * kPio2_3;
    r = t - w;
    w = n * kPio2_3t - ((t - r) - w);
    const double y0 = r - w;
    const double y1 = (r - y0) - w;

    const double s = sincos_detail::sineKernel(y0, y1), c = sincos_detail::cosineKernel(y0, y1);
    switch (static_cast<long long>(n) & 3)
    {
        case 0:
            sine = s;
            cosine = c;
            break;
        case 1:
            sine = c;
            cosine = -s;
            break;
        case 2:
            sine = -s;
            cosine = -c;
            break;
        default:
            sine = -c;
            cosine = s;
            break;
    }
}
}  // namespace rastercheck::device
