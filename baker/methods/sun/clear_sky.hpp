// The clear-sky irradiance model of the European Solar Radiation Atlas (Rigollier, Bauer & Wald 2000, "On
// the clear sky model of the ESRA with respect to the Heliosat method", Solar Energy 68(1)), the model GRASS
// r.sun uses (Suri & Hofierka 2004): beam and diffuse irradiance from the sun's elevation, the Linke
// turbidity factor and the site's height. Formulas and their symbols: docs/gis.md, "Sunlight over time".
#pragma once

namespace hfbake::sun {

// The sun's elevation with the model's refraction correction (radians in, radians out; Rigollier 2000
// Eq. 5, used for the air mass only).
double refracted_elevation(double elevation);

// Relative optical air mass at sea level (Kasten & Young 1989 as ESRA writes it) for a sun at geometric
// elevation `elevation` (radians, > 0); a site at height z has p/p0 = exp(-z / 8434.5) times it.
double relative_air_mass(double elevation);

// Rayleigh optical thickness at air mass m (Kasten 1996, as ESRA writes it).
double rayleigh_thickness(double m);

// Beam irradiance normal to the sun's rays (W/m^2): extraterrestrial `g0` attenuated over air mass m (the
// site's, pressure-corrected) with Linke turbidity `linke`: g0 exp(-0.8662 T_LK m delta_R(m)).
double beam_normal(double g0, double m, double linke);

// Diffuse irradiance on an unobstructed horizontal surface (W/m^2) for a sun at elevation `elevation`
// (radians, > 0): g0 T_n(T_LK) F_d(elevation).
double diffuse_horizontal(double g0, double elevation, double linke);

// exp(-z / 8434.5): the pressure ratio p/p0 at height z metres (the air mass's correction).
double pressure_ratio(double z);

}  // namespace hfbake::sun
