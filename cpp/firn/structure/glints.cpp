#include "firn/structure/glints.h"

#include <cmath>
#include <string>

#include "firn/optics/fresnel.h"
#include "firn/util/error.h"
#include "firn/util/sampling.h"

namespace firn {

void GlintSettings::validate() const {
    if (!(facetRadius > 0.0 && facetRadius < 0.1))
        throw InvalidArgument("glint facet radius must be in (0, 0.1) m, got " + std::to_string(facetRadius));
    const double most = 1.0 / (4.0 * facetRadius * facetRadius);
    if (!(facetsPerSquareMetre > 0.0 && facetsPerSquareMetre <= most))
        throw InvalidArgument("glint density must be in (0, " + std::to_string(most) + "] facets per m^2 for facets of " +
                              std::to_string(facetRadius * 1e3) + " mm, got " + std::to_string(facetsPerSquareMetre));
}

GlintFacets glintFacets(const GlintSettings &settings) {
    settings.validate();
    GlintFacets facets;
    facets.cellSize = std::cbrt(2.0 * settings.facetRadius / settings.facetsPerSquareMetre);
    facets.balls = {settings.facetRadius / facets.cellSize, 0.0};
    facets.coverage = cellBallMeans(facets.balls).coverage;
    return facets;
}

double meanGlintRadiance(double coverage, double eta, double cosHalfAngle) {
    if (!(cosHalfAngle > 0.0 && cosHalfAngle <= 1.0)) throw InvalidArgument("cos of the half angle must be in (0, 1]");
    return coverage * fresnelReflectance(cosHalfAngle, eta) / (8.0 * kPi * cosHalfAngle);
}

double glintFraction(double coverage, double sunSolidAngle, double cosHalfAngle) {
    if (!(cosHalfAngle > 0.0 && cosHalfAngle <= 1.0)) throw InvalidArgument("cos of the half angle must be in (0, 1]");
    if (!(sunSolidAngle >= 0.0)) throw InvalidArgument("the sun's solid angle must be >= 0 sr");
    return coverage * sunSolidAngle / (8.0 * kPi * cosHalfAngle);
}

}  // namespace firn
