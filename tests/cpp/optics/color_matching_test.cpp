#include "firn/optics/color_matching.h"

#include <cmath>

#include <gtest/gtest.h>

namespace firn {

namespace {

Spectrum flat(double value) {
    Spectrum s{};
    s.fill(value);
    return s;
}

}  // namespace

// CIE 1931 2-degree colour-matching functions as tabulated by the CIE (ISO 11664-1), at 30 nm steps.
TEST(ColorMatching, FitFollowsTheCie1931Table) {
    struct Row {
        double nm, x, y, z;
    };
    const Row table[] = {
        {400, 0.01431, 0.000396, 0.06785}, {430, 0.2839, 0.0116, 1.3856},  {460, 0.2908, 0.06, 1.6692},
        {490, 0.03201, 0.20802, 0.46518},  {520, 0.06327, 0.71, 0.07825},  {550, 0.43345, 0.99495, 0.00875},
        {580, 0.9163, 0.87, 0.00165},      {610, 1.0026, 0.503, 0.00034},  {640, 0.4479, 0.175, 0.00002},
        {670, 0.0874, 0.032, 0.0},         {700, 0.011359, 0.004102, 0.0},
    };
    for (const Row &row : table) {
        const glm::dvec3 fit = cie1931Xyz(row.nm);
        // Wyman, Sloan & Shirley (2013) fit the table to about 1 % of the peaks.
        EXPECT_NEAR(fit.x, row.x, 0.015) << row.nm << " nm";
        EXPECT_NEAR(fit.y, row.y, 0.015) << row.nm << " nm";
        EXPECT_NEAR(fit.z, row.z, 0.015) << row.nm << " nm";
    }
}

TEST(ColorMatching, FitHasTheTableIntegrals) {
    // The CIE 1931 functions integrate to 106.857 each over 360-830 nm (1 nm sums): equal-energy white.
    glm::dvec3 sum(0.0);
    for (int nm = 360; nm <= 830; ++nm) sum += cie1931Xyz(nm);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c] / 106.857, 1.0, 3e-3) << c;
}

TEST(ColorMatching, MatrixIsTheSrgbStandardOne) {
    // IEC 61966-2-1 (sRGB), XYZ -> linear RGB, given to 4 decimals.
    const double standard[3][3] = {{3.2406, -1.5372, -0.4986}, {-0.9689, 1.8758, 0.0415}, {0.0557, -0.2040, 1.0570}};
    const glm::dmat3 &m = xyzToRec709();
    for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 3; ++col) EXPECT_NEAR(m[col][row], standard[row][col], 6e-4) << row << "," << col;
    // D65 white (x, y) = (0.3127, 0.3290) at Y = 1 is RGB white.
    const Rgb white = m * glm::dvec3(0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(white[c], 1.0, 1e-12);
}

TEST(ColorMatching, LuminanceIsRec709) {
    EXPECT_NEAR(rec709Luminance(Rgb(1, 0, 0)), 0.2126, 1e-4);
    EXPECT_NEAR(rec709Luminance(Rgb(0, 1, 0)), 0.7152, 1e-4);
    EXPECT_NEAR(rec709Luminance(Rgb(0, 0, 1)), 0.0722, 1e-4);
}

TEST(ColorMatching, FlatSpectrumIsGrey) {
    for (double value : {0.0, 0.37, 1.0}) {
        const Rgb rgb = spectrumToRgb(flat(value));
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(rgb[c], value, 1e-14);
    }
}

TEST(ColorMatching, ChannelsSeeTheirOwnPartOfTheSpectrum) {
    // A reflectance that is 1 only in one part of the band raises mainly the matching channel.
    auto band = [](double fromNm, double toNm) {
        Spectrum s{};
        for (std::size_t i = 0; i < kSpectrumSamples; ++i)
            s[i] = (spectrumWavelengthNm(i) >= fromNm && spectrumWavelengthNm(i) <= toNm) ? 1.0 : 0.0;
        return s;
    };
    const Rgb blue = spectrumToRgb(band(390, 490)), green = spectrumToRgb(band(500, 570)),
              red = spectrumToRgb(band(600, 800));
    EXPECT_GT(blue.b, blue.g);
    EXPECT_GT(blue.b, blue.r);
    EXPECT_GT(green.g, green.r);
    EXPECT_GT(green.g, green.b);
    EXPECT_GT(red.r, red.g);
    EXPECT_GT(red.r, red.b);
}

TEST(ColorMatching, ReflectanceStaysWithinZeroToOneAtConstantLuminance) {
    // Black below 560 nm, white above: a saturated orange whose projection leaves [0, 1].
    Spectrum orange{};
    for (std::size_t i = 0; i < kSpectrumSamples; ++i) orange[i] = spectrumWavelengthNm(i) < 560 ? 0.0 : 1.0;
    const Rgb projected = spectrumToRgb(orange);
    ASSERT_TRUE(projected.r > 1.0 || projected.b < 0.0) << "the test needs an out-of-gamut spectrum";
    const Rgb mapped = reflectanceToRgb(orange);
    for (int c = 0; c < 3; ++c) {
        EXPECT_GE(mapped[c], 0.0);
        EXPECT_LE(mapped[c], 1.0);
    }
    EXPECT_NEAR(rec709Luminance(mapped), rec709Luminance(projected), 1e-12);
    EXPECT_GT(mapped.r, mapped.g);  // still orange
    EXPECT_GT(mapped.g, mapped.b);
    // A colour inside the gamut is left alone.
    Spectrum pale{};
    for (std::size_t i = 0; i < kSpectrumSamples; ++i) pale[i] = 0.9 + 0.05 * std::sin(0.1 * double(i));
    const Rgb paleRgb = reflectanceToRgb(pale), paleProjected = spectrumToRgb(pale);
    for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(paleRgb[c], paleProjected[c]);
}

}  // namespace firn
