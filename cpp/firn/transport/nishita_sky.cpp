#include "firn/transport/nishita_sky.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/util/error.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

// The atmosphere and the spectral data are those Blender 3.4 gives Nishita et al. 1993's model (intern/sky):
// the sky must read as Cycles renders it.
constexpr double kEarthRadius = 6360e3;       // m
constexpr double kAtmosphereRadius = 6420e3;  // m: the top of the atmosphere
constexpr double kAirScaleHeight = 8e3;       // m, Rayleigh
constexpr double kDustScaleHeight = 1.2e3;    // m, Mie
constexpr double kDustScattering = 2e-5;      // 1/m at sea level, every wavelength
constexpr double kDustExtinctionPerScattering = 1.11;  // dust absorbs a tenth of what it meets (albedo 0.9)
constexpr double kDustAsymmetry = 0.76;       // Cornette-Shanks g
constexpr int kViewSteps = 32;                // midpoint segments along the view ray, as Blender
constexpr double kMinSunSize = 0.0005;        // rad: Cycles' smallest disc (a zero Sun Size has one too)
// m: the viewer kept 1 m above the ground (a ray from the surface itself grazes it) and below the top.
constexpr double kMinAltitude = 1.0, kMaxAltitude = 59999.0;

constexpr int kWavelengths = 21;  // 380, 400, ..., 780 nm
constexpr double kWavelengthStep = 20.0;  // nm
using Spectrum = std::array<double, kWavelengths>;

// Sunlight at the top of the atmosphere, W/m^2/nm.
constexpr Spectrum kSolarIrradiance = {
    1.45756829855593, 1.56596305559738, 1.65148449067670, 1.71496242737209, 1.75797983805021, 1.78256407885925,
    1.79095108475839, 1.78541550133411, 1.76815554864307, 1.74122069647250, 1.70647127164944, 1.66556087452740,
    1.61993437242452, 1.57083597368892, 1.51932335059305, 1.46628494965214, 1.41245852740172, 1.35844961970384,
    1.30474913844739, 1.25174963272611, 1.19975998755421};
// Rayleigh scattering of air at sea level, 1/m (~ 1 / lambda^4).
constexpr Spectrum kAirScattering = {
    5.424820087636473e-5, 4.418549866505454e-5, 3.635151910165377e-5, 3.017929012024763e-5, 2.526320226989157e-5,
    2.130859310621843e-5, 1.809838025320633e-5, 1.547057129129042e-5, 1.330284977336850e-5, 1.150184784075764e-5,
    9.99557429990163e-6,  8.72799973630707e-6,  7.65513700977967e-6,  6.74217203751443e-6,  5.96134125832052e-6,
    5.29034598065810e-6,  4.71115687557433e-6,  4.20910481110487e-6,  3.77218381260133e-6,  3.39051255477280e-6,
    3.05591531679811e-6};
// Ozone absorption at the ozone layer's peak (25 km), 1/m: the Chappuis band around 600 nm.
constexpr Spectrum kOzoneAbsorption = {
    3.25126849861e-9, 5.85395365047e-9, 1.977191155085e-8, 7.309568762914e-8, 2.0084561514287e-7,
    4.0383958096161e-7, 6.3551335912363e-7, 9.6707041180970e-7, 1.54797400424410e-6, 2.09038647223331e-6,
    2.46128056164565e-6, 2.73551299461512e-6, 2.15125863128643e-6, 1.59051840791988e-6, 1.12356197979857e-6,
    7.3527551487574e-7, 4.6450130357806e-7, 3.3096079921048e-7, 2.2512612292678e-7, 1.4879129266490e-7,
    1.6828623364192e-7};
// CIE 1931 2-degree colour matching functions x, y, z at the same wavelengths.
constexpr std::array<std::array<double, 3>, kWavelengths> kCie1931 = {{
    {0.0013680, 0.0000390, 0.0064500}, {0.0143100, 0.0003960, 0.0678500}, {0.1343800, 0.0040000, 0.6456000},
    {0.3482800, 0.0230000, 1.7470600}, {0.2908000, 0.0600000, 1.6692000}, {0.0956400, 0.1390200, 0.8129501},
    {0.0049000, 0.3230000, 0.2720000}, {0.0632700, 0.7100000, 0.0782500}, {0.2904000, 0.9540000, 0.0203000},
    {0.5945000, 0.9950000, 0.0039000}, {0.9163000, 0.8700000, 0.0016500}, {1.0622000, 0.6310000, 0.0008000},
    {0.8544499, 0.3810000, 0.0001900}, {0.4479000, 0.1750000, 0.0000200}, {0.1649000, 0.0610000, 0.0},
    {0.0467700, 0.0170000, 0.0},       {0.0113592, 0.0041020, 0.0},       {0.0028993, 0.0010470, 0.0},
    {0.0006901, 0.0002492, 0.0},       {0.0001662, 0.0000600, 0.0},       {0.0000415, 0.0000150, 0.0}}};

// CIE XYZ -> linear Rec.709 (the inverse of IEC 61966-2-1's matrix, D65), Blender 3.4's scene linear.
Rgb rec709FromXyz(const glm::dvec3 &xyz) {
    return {3.2404542 * xyz.x - 1.5371385 * xyz.y - 0.4985314 * xyz.z,
            -0.9692660 * xyz.x + 1.8760108 * xyz.y + 0.0415560 * xyz.z,
            0.0556434 * xyz.x - 0.2040259 * xyz.y + 1.0572252 * xyz.z};
}

Rgb rgbFromSpectrum(const Spectrum &radiance) {
    glm::dvec3 xyz(0.0);
    for (int i = 0; i < kWavelengths; ++i)
        xyz += radiance[i] * glm::dvec3(kCie1931[i][0], kCie1931[i][1], kCie1931[i][2]);
    return glm::max(rec709FromXyz(xyz * kWavelengthStep), Rgb(0.0));  // a colour out of gamut clips
}

// Air, dust and ozone at `height` (m above sea level), relative to sea level (air, dust) or the ozone peak:
// exponential air and dust, ozone a tent from 10 to 40 km peaking at 25 km.
glm::dvec3 densityProfile(double height) {
    const double ozone = std::max(0.0, 1.0 - std::abs(height - 25e3) / 15e3);
    return {std::exp(-height / kAirScaleHeight), std::exp(-height / kDustScaleHeight), ozone};
}

// Rayleigh phase function (1/sr) at the cosine mu between the light's and the view's directions.
double rayleighPhase(double mu) { return 3.0 / (16.0 * kPi) * (1.0 + mu * mu); }

// Cornette & Shanks 1992's phase function (1/sr), a Henyey-Greenstein with Rayleigh's 1 + mu^2.
double miePhase(double mu) {
    const double g = kDustAsymmetry, g2 = g * g;
    return 3.0 * (1.0 - g2) * (1.0 + mu * mu) / (8.0 * kPi * (2.0 + g2) * std::pow(1.0 + g2 - 2.0 * g * mu, 1.5));
}

// Distance (m) from `origin`, inside a sphere about the Earth's centre of `radius`, to where the ray leaves it.
double exitDistance(const glm::dvec3 &origin, const glm::dvec3 &direction, double radius) {
    const double b = glm::dot(origin, direction);
    return -b + std::sqrt(std::max(0.0, b * b - glm::dot(origin, origin) + radius * radius));
}

bool hitsEarth(const glm::dvec3 &origin, const glm::dvec3 &direction) {
    const double b = glm::dot(origin, direction);
    return b < 0.0 && glm::dot(origin, origin) - b * b < kEarthRadius * kEarthRadius;
}

// Column densities (m, per unit of sea-level air and dust and of peak ozone) from `origin` to space along
// `direction`. The densities fall about exponentially along the ray, so Gauss-Laguerre quadrature (8 nodes,
// Abramowitz & Stegun 25.4.45) of g(x) = f(x) e^x, the ray's length mapped to x in [0, 25] so that the last
// node stays inside the atmosphere.
glm::dvec3 columnToSpace(const glm::dvec3 &origin, const glm::dvec3 &direction) {
    static constexpr std::array<double, 8> kNodes = {0.170279632305101, 0.903701776799380, 2.251086629866131,
                                                     4.266700170287659, 7.045905402393466, 10.75851601018100,
                                                     15.74067864127800, 22.86313173688926};
    static constexpr std::array<double, 8> kWeights = {3.69188589341638e-1, 4.18786780814343e-1,
                                                       1.75794986637172e-1, 3.33434922612157e-2,
                                                       2.79453623522567e-3, 9.07650877335821e-5,
                                                       8.48574671627253e-7, 1.04800117487151e-9};
    constexpr double kSpan = 25.0;
    const double length = exitDistance(origin, direction, kAtmosphereRadius);
    glm::dvec3 column(0.0);
    for (std::size_t i = 0; i < kNodes.size(); ++i) {
        const glm::dvec3 p = origin + (kNodes[i] / kSpan * length) * direction;
        column += kWeights[i] * std::exp(kNodes[i]) / kSpan * densityProfile(glm::length(p) - kEarthRadius);
    }
    return column * length;
}

double clampedAltitude(const NishitaSky &sky) { return std::clamp(sky.altitude, kMinAltitude, kMaxAltitude); }

glm::dvec3 viewer(const NishitaSky &sky) { return {0.0, 0.0, kEarthRadius + clampedAltitude(sky)}; }

// Optical depth at wavelength i of a column (air, dust, ozone) already scaled by the sky's densities.
double opticalDepth(const glm::dvec3 &column, int i) {
    return column.x * kAirScattering[i] + column.y * kDustExtinctionPerScattering * kDustScattering +
           column.z * kOzoneAbsorption[i];
}

// Sunlight scattered once towards the viewer along `view` (unit, above the horizon), W/m^2/sr/nm: Nishita's
// sum over segments of T(viewer, P) T(P, sun) sigma_s(P) p(mu) E_sun. Each segment is taken at its midpoint
// with the view ray's transmittance to its far end, as Blender's 32-step rule (kept so the horizon matches).
Spectrum inscattered(const NishitaSky &sky, const glm::dvec3 &view, const glm::dvec3 &sun) {
    const glm::dvec3 origin = viewer(sky);
    const glm::dvec3 densities(sky.airDensity, sky.dustDensity, sky.ozoneDensity);
    const double step = exitDistance(origin, view, kAtmosphereRadius) / kViewSteps;
    const double mu = glm::dot(view, sun);
    const double airPhase = rayleighPhase(mu), dustPhase = miePhase(mu);
    Spectrum radiance{};
    glm::dvec3 viewColumn(0.0);
    for (int s = 0; s < kViewSteps; ++s) {
        const glm::dvec3 p = origin + ((s + 0.5) * step) * view;
        const glm::dvec3 density = densities * densityProfile(glm::length(p) - kEarthRadius);
        viewColumn += density * step;
        if (hitsEarth(p, sun)) continue;  // in the Earth's shadow
        const glm::dvec3 column = viewColumn + densities * columnToSpace(p, sun);
        for (int i = 0; i < kWavelengths; ++i) {
            const double scattering = density.x * kAirScattering[i] * airPhase + density.y * kDustScattering * dustPhase;
            radiance[i] += std::exp(-opticalDepth(column, i)) * scattering * kSolarIrradiance[i] * step;
        }
    }
    return radiance;
}

double elevationOf(const glm::dvec3 &direction) { return std::asin(std::clamp(direction.z, -1.0, 1.0)); }

// Angle (rad) between unit vectors, accurate for small angles.
double angleBetween(const glm::dvec3 &a, const glm::dvec3 &b) {
    return 2.0 * std::atan2(glm::length(a - b), glm::length(a + b));
}

double sunSizeOf(const NishitaSky &sky) { return std::max(sky.sunSize, kMinSunSize); }

// The disc as Cycles draws it: the radiance of the sun seen at its lowest and highest points (each clamped to
// the horizon), interpolated in elevation across the disc.
struct SunDisc {
    glm::dvec3 centre;
    double elevation, halfAngle;
    Rgb bottom, top;  // W/m^2/sr, strength and intensity included
};

// Radiance of the sun seen at `elevation` (rad >= 0): its irradiance through the atmosphere spread evenly over
// the disc's solid angle. Blender's disc leaves ozone out; so does this.
Rgb sunRadianceAt(const NishitaSky &sky, double elevation) {
    const glm::dvec3 view(std::cos(elevation), 0.0, std::sin(elevation));
    const glm::dvec3 column = glm::dvec3(sky.airDensity, sky.dustDensity, 0.0) * columnToSpace(viewer(sky), view);
    const double solidAngle = 2.0 * kPi * (1.0 - std::cos(0.5 * sunSizeOf(sky)));
    Spectrum radiance{};
    for (int i = 0; i < kWavelengths; ++i)
        radiance[i] = kSolarIrradiance[i] * std::exp(-opticalDepth(column, i)) / solidAngle;
    return rgbFromSpectrum(radiance) * (sky.sunIntensity * sky.strength);
}

SunDisc sunDisc(const NishitaSky &sky) {
    const double half = 0.5 * sunSizeOf(sky);
    return {sunDirection(sky), sky.sunElevation, half,
            sunRadianceAt(sky, std::max(sky.sunElevation - half, 0.0)),
            sunRadianceAt(sky, std::max(sky.sunElevation + half, 0.0))};
}

Rgb discRadiance(const SunDisc &disc, const glm::dvec3 &direction) {
    const double angle = angleBetween(direction, disc.centre);
    const double lowest = disc.elevation - disc.halfAngle, highest = disc.elevation + disc.halfAngle;
    if (angle >= disc.halfAngle || direction.z < 0.0 || highest <= 0.0) return Rgb(0.0);
    const double elevation = elevationOf(direction);
    // Across the disc from bottom to top; a disc cut by the horizon spans from the horizon up.
    const double t = lowest > 0.0 ? (elevation - lowest) / (highest - lowest) : elevation / highest;
    const double r = angle / disc.halfAngle;
    const double limbDarkening = 1.0 - 0.6 * (1.0 - std::sqrt(1.0 - r * r));  // Blender's coefficient 0.6
    return ((1.0 - t) * disc.bottom + t * disc.top) * limbDarkening;
}

}  // namespace

glm::dvec3 sunDirection(const NishitaSky &sky) {
    const double e = sky.sunElevation, r = sky.sunRotation;
    return {std::sin(r) * std::cos(e), std::cos(r) * std::cos(e), std::sin(e)};
}

Rgb skyRadiance(const NishitaSky &sky, const glm::dvec3 &direction) {
    constexpr double kBlackBelow = -0.4;  // direction z below which Blender's ground is black
    if (direction.z < kBlackBelow) return Rgb(0.0);
    if (direction.z < 0.0) {
        const double fade = 1.0 + direction.z / -kBlackBelow;
        return fade * fade * fade * skyRadiance(sky, glm::normalize(glm::dvec3(direction.x, direction.y, 0.0)));
    }
    return rgbFromSpectrum(inscattered(sky, direction, sunDirection(sky))) * sky.strength;
}

Rgb sunDiscRadiance(const NishitaSky &sky, const glm::dvec3 &direction) {
    if (!sky.sunDisc) return Rgb(0.0);
    return discRadiance(sunDisc(sky), direction);
}

std::optional<SunLight> nishitaSun(const NishitaSky &sky) {
    if (!sky.sunDisc || sky.sunIntensity <= 0.0 || sky.strength <= 0.0) return std::nullopt;
    const SunDisc disc = sunDisc(sky);
    // E = integral over the disc of L cos(psi) dOmega, dOmega = sin(psi) dpsi dphi: midpoints in psi and phi.
    constexpr int kRings = 64, kSectors = 64;
    const double dPsi = disc.halfAngle / kRings, dPhi = 2.0 * kPi / kSectors;
    Rgb irradiance(0.0);
    for (int i = 0; i < kRings; ++i) {
        const double psi = (i + 0.5) * dPsi;
        for (int j = 0; j < kSectors; ++j) {
            const glm::dvec3 d = directionAround(disc.centre, std::cos(psi), (j + 0.5) * dPhi);
            irradiance += discRadiance(disc, d) * (std::cos(psi) * std::sin(psi) * dPsi * dPhi);
        }
    }
    if (std::max({irradiance.x, irradiance.y, irradiance.z}) <= 0.0) return std::nullopt;
    return SunLight{disc.centre, irradiance, sunSizeOf(sky)};
}

std::vector<Rgb> nishitaSkyMap(const NishitaSky &sky, const glm::dmat3 &toWorld, int width, int height, int samples) {
    if (width < 1 || height < 1 || double(width) * height > 1 << 24)
        throw InvalidArgument("sky map size must be between 1 x 1 and 16M pixels");
    if (samples < 1 || samples > 16) throw InvalidArgument("sky map samples per pixel axis must be 1 to 16");
    validate(sky);
    std::vector<Rgb> pixels(std::size_t(width) * height);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pixels.size(), 16), [&](const auto &range) {
        for (std::size_t index = range.begin(); index != range.end(); ++index) {
            const double column = double(index % width), row = double(index / width);
            Rgb sum(0.0);
            for (int a = 0; a < samples; ++a)
                for (int b = 0; b < samples; ++b) {
                    const double u = (column + (a + 0.5) / samples) / width, v = (row + (b + 0.5) / samples) / height;
                    sum += skyRadiance(sky, glm::normalize(toWorld * EnvironmentMap::directionFromUv(u, v)));
                }
            pixels[index] = sum / double(samples * samples);
        }
    });
    return pixels;
}

void validate(const NishitaSky &sky) {
    auto within = [](double value, double low, double high) { return std::isfinite(value) && value >= low && value <= high; };
    if (!within(sky.sunElevation, -kPi / 2, kPi / 2)) throw InvalidArgument("sun elevation must be -pi/2 to pi/2 rad");
    if (!std::isfinite(sky.sunRotation)) throw InvalidArgument("sun rotation must be finite");
    if (!within(sky.sunSize, 0.0, kPi / 2)) throw InvalidArgument("sun size must be 0 to pi/2 rad");
    if (!within(sky.sunIntensity, 0.0, 1e9)) throw InvalidArgument("sun intensity must be non-negative");
    if (!within(sky.altitude, 0.0, 60e3)) throw InvalidArgument("altitude must be 0 to 60000 m");
    if (!within(sky.airDensity, 0.0, 10.0)) throw InvalidArgument("air density must be 0 to 10");
    if (!within(sky.dustDensity, 0.0, 10.0)) throw InvalidArgument("dust density must be 0 to 10");
    if (!within(sky.ozoneDensity, 0.0, 10.0)) throw InvalidArgument("ozone density must be 0 to 10");
    if (!within(sky.strength, 0.0, 1e9)) throw InvalidArgument("background strength must be non-negative");
}

}  // namespace firn
