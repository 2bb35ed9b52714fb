#pragma once

#include <cstdint>
#include <vector>

namespace firn {

// The sun light a thick snow surface returns, in the form the baked grids store (radiance linear in the
// outgoing direction w):
//   pi L(w) / (mu0 E) = A (a + b (n . w) + c (t . w)),   a + 2b/3 = 1
// n the surface normal, t the unit tangent pointing where the sun's light travels (forward), mu0 the cosine
// of the sun's incidence, E its irradiance at normal incidence. A is the half-space's plane albedo (the
// fraction of the sun's flux that returns) and (a, b, c) the shape of what returns: the reflection function
// of a half-space with a Henyey-Greenstein phase function (all orders), fitted by least squares in relative
// error over the outgoing hemisphere, weighted by projected solid angle, with the flux fixed. Absorption
// changes both: what returns after few scatterings keeps the sun's direction, and absorption takes most from
// the long paths that would have spread it.
struct SunLobe {
    double a = 1.0, b = 0.0, c = 0.0;
    double albedo = 1.0;  // A(mu0)
};

// The returned sun split in two (the half-space's reflection function R over its albedo A, exitance 1):
//   R(w) / A = share P(w) + (1 - share) rest (a + b (n . w) + c (t . w)),   a + 2b/3 = 1,
// P a peaked Henyey-Greenstein lobe of anisotropy k about the axis `elevation` above the horizon towards t,
// scaled to exitance 1: share P(w) = lobeRadiance(mean, 3 k m, w) (source_lobe.h, m unit), so that a surface
// returning exitance M stores the peaked lobe of l0 = mean M / pi. At grazing sun a half-space returns light
// sharply forwards, towards grazing exit (R / A 3 at grazing forward exit for mu0 = 0.5, 13-16 for mu0 = 0.28
// at g 0.85, omega 0.98), which neither the linear form nor a broad lobe holds; the grids' second, peaked lobe
// holds it, the broad lobe the rest. Fitted like the sun lobe (relative error, projected solid angle; 40,000
// photons per entry), k and elevation by search; share 0 where no peak fits better than the linear form alone.
// rest is 1 (the exitance kept) but under a low sun (kRenderedRestMu0).
struct SunPeak {
    double share = 0.0, mean = 0.0, k = 0.0, elevation = 0.0;  // elevation in radians
    double b = 0.0, c = 0.0;
    double rest = 1.0;
    double a() const { return 1.0 - 2.0 * b / 3.0; }
};
constexpr double kMinPeakElevationDegrees = 5.0;  // the axis above the horizon: a lobe pointing into the snow
                                                  // hides its mean where no camera looks
// Below this sun cosine (a sun under 11.5 deg) the half-space's first order peaks at grazing exit, narrower than a
// lobe about an axis 5 deg up follows: fitted so, the lobe lowered its k and its flank carried the peak up to where
// cameras look (towards the sun +30 to +80 % over flat snow; docs/benchmarks.md, grazing-peak). There the axis may
// come down to 2.5 deg: on the horizon the flat snow gained more, but a ball's limb, seen at grazing exit, took the
// half-space's grazing peak where its curved rim returns less (docs/benchmarks.md, grazing-refit).
constexpr double kGrazingSunMu0 = 0.2, kGrazingPeakElevationDegrees = 2.5;
constexpr double kMaxPeakShare = 0.9;
// Below this sun cosine (a sun under 17.5 deg, where the split stands alone: kPeakFadeStart) the split is fitted as
// the grids render it, the rest as its broad lobe (exitLobe), and the rest's exitance free up to 1 - share. A low
// sun's half-space returns most at grazing exits of every azimuth (single scattering goes as 1 / (mu0 + mu)), which
// one Henyey-Greenstein lobe cannot lean to: the linear rest (b -2) so rendered sent 2.5 times its light straight
// up, the exitance kept; the fit gives up part of the rest's light at grazing exit (to 0.7 of it at the issue's
// snow, 3 deg) for the views above it, and keeps the split's grazing exits under what the half-space returns
// (a ball's limb is seen there) (docs/benchmarks.md, grazing-rim).
constexpr double kRenderedRestMu0 = 0.3;
// Where the surface curves, cameras see a patch's grazing exits at the limb: the light the low sun's split gives up
// there (1 - SunPeak::rest of its rest, which a flat top shows only through its ramp) is light a ball's limb and rim
// lack (docs/benchmarks.md, against-sun). A surface curving as a sphere of kRestKeptRadius voxels or faster keeps the
// rest's exitance (1 - share); flatter ones keep what the flat fit gives up in proportion to the curvature.
constexpr double kRestKeptRadius = 10.0;  // voxels
// The rest's exitance over 1 - share on a surface of this curvature (per voxel, positive convex: surfaceCurvature).
double restKept(const SunPeak &split, double curvaturePerVoxel);
// sunPeak fades the split into the sun lobe alone (share 0, SunLobe's b and c) between these sun cosines.
constexpr double kPeakFadeStart = 0.3, kPeakFadeEnd = 0.6;

// The similarity parameter of absorption, y = 4 sqrt((1 - omega) / (3 (1 - g))) (Kokhanovsky & Zege 2004:
// the spherical albedo of a weakly absorbing half-space is exp(-y)); the table's third axis.
double absorptionParameter(double omega, double g);

// Trilinear in (y, g, mu0) from the precomputed table (sun_lobe_table.inc); g clamped to [0, 0.95],
// y to [0, 4] (omega down to 0.75 at g = 0.85).
SunLobe sunLobe(double g, double mu0, double y = 0.0);

// The spherical albedo of a half-space of this snow, 2 int A(mu) mu dmu over the table's plane albedo A: the
// share of uniform sky light it returns (by reciprocity, towards mu it returns L_sky A(mu)).
double sphericalAlbedo(double g, double y);

// Interpolated in (y, g, mu0) like sunLobe, from sun_peak_table.inc; `lobe` = sunLobe(g, mu0, y), which the
// split fades into (the caller has it already).
SunPeak sunPeak(double g, double mu0, double y, const SunLobe &lobe);

// The tables' source, used by tools/sun_lobe_table.cpp and the tests (the bake reads the tables alone): 1D Monte Carlo
// of a half-space with analog absorption; photons deeper than 30 transport mean free paths return with diffusion's
// probability exp(-kappa (z + z_b)) in the escape function's shape.
SunLobe fitSunLobe(double g, double mu0, double y, long photons, std::uint64_t seed);
SunPeak fitSunPeak(double g, double mu0, double y, long photons, std::uint64_t seed);

// The limb darkening the grids miss on a flat snow surface (docs/benchmarks.md, limb-own): per outgoing bin (cos
// zenith mu over kLimbMuBins, the azimuth off the sun's travel over kLimbAzimuthBins, 0 forward), D such that the
// split sunPeak writes renders the half-space exactly when its rest's broad lobe is D times darker or brighter:
//   R / A_table = P(w) + D(w) rest(w),
// R the half-space's reflection function (Monte Carlo, as the table's), P the split's peaked lobe and rest its broad
// lobe (exitLobe of the linear rest, exitance (1 - share) rest) as the grids render them, bin means. Not a fit: the
// truth over the bake's own lobes. Used by tools/sun_lobe_table.cpp (`limb`) alone, yet kept here beside the fits:
// it is their Monte Carlo over their outgoing bins (the fits' bins are these) with the same bin means of the rendered
// lobes, which the tool would otherwise copy or this header export; half_space_test checks it as it checks them.
constexpr int kLimbMuBins = 20, kLimbAzimuthBins = 18;
// Each bin also holds P and rest as rendered (bin means, the split's exitance 1): their flux over the bins is the
// exitance the grids show, and D's flux mean over some bins says whether D adds light there or moves it
// (docs/benchmarks.md, limb-rule: from mu0 0.3 up the lobes keep the half-space's exitance).
struct LimbBin {
    double mu = 0.0, azimuth = 0.0;  // bin centre; radians
    double darkening = 1.0;
    double peak = 0.0, broad = 0.0;  // P and rest, bin means
};
std::vector<LimbBin> limbDarkening(double g, double mu0, double y, long photons, std::uint64_t seed);

}  // namespace firn
