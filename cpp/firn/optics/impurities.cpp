#include "firn/optics/impurities.h"

#include <cmath>

namespace firn {

double massAbsorption(const ImpurityAbsorption &impurity, double wavelength) {
    return impurity.mac550 * std::pow(550e-9 / wavelength, impurity.angstrom);
}

}  // namespace firn
