#pragma once

#include <optional>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "firn/transport/lights.h"
#include "firn/util/color.h"

namespace firn {

// Blender's Sky Texture of type Nishita behind a Background node: the sky of Nishita et al. 1993 ("Display of
// the Earth taking into account atmospheric scattering", SIGGRAPH), single scattering of sunlight by air
// (Rayleigh) and dust (Mie) with ozone absorption, in a spherical atmosphere over a spherical Earth, sampled
// at 21 wavelengths and seen in linear Rec.709 RGB, as Cycles 3.4 renders it. Settings as the node's Python
// properties hold them (angles in rad).
struct NishitaSky {
    double sunElevation = 0.2617993877991494;  // rad above the horizon (Blender's default 15 deg)
    double sunRotation = 0.0;                  // rad about +Z: 0 puts the sun towards +Y, turning towards +X
    double sunSize = 0.009512044423369096;     // rad, the disc's angular diameter (default 0.545 deg)
    double sunIntensity = 1.0;                 // scales the disc only
    bool sunDisc = true;
    double altitude = 0.0;                     // m above sea level, 0 to 60 km
    double airDensity = 1.0;                   // scales the air (Rayleigh scattering), 0 to 10
    double dustDensity = 1.0;                  // scales the dust (Mie scattering and absorption), 0 to 10
    double ozoneDensity = 1.0;                 // scales the ozone layer (absorption), 0 to 10
    double strength = 1.0;                     // the Background node's Strength
};

// Unit world direction towards the sun's centre.
glm::dvec3 sunDirection(const NishitaSky &sky);

// Radiance (W/m^2/sr) of the sky without its sun disc arriving from `direction` (unit, world, pointing away
// from the scene). Below the horizon Blender fades the horizon's colour to black at 23.6 deg down (its
// convention for a ground it does not model).
Rgb skyRadiance(const NishitaSky &sky, const glm::dvec3 &direction);

// Radiance (W/m^2/sr) of the sun disc at `direction`, zero outside the disc or below the horizon: the
// sunlight left after the air and dust between the top of the atmosphere and the viewer, spread over the
// disc with Blender's limb darkening.
Rgb sunDiscRadiance(const NishitaSky &sky, const glm::dvec3 &direction);

// The sun disc as a Sun lamp: its irradiance (W/m^2 on a plane facing it) integrated over the disc above the
// horizon; none when the disc is off, dark or wholly below the horizon.
std::optional<SunLight> nishitaSun(const NishitaSky &sky);

// The sky without its disc as the pixels of an equirectangular EnvironmentMap (its convention and layout), for
// a frame whose directions turn into world directions by `toWorld` (a rotation): each pixel the mean of
// samples x samples directions spread over it, as a renderer's box-filtered pixel. Parallel (TBB).
std::vector<Rgb> nishitaSkyMap(const NishitaSky &sky, const glm::dmat3 &toWorld, int width, int height, int samples);

// Throws InvalidArgument naming the first setting out of Blender's range.
void validate(const NishitaSky &sky);

}  // namespace firn
