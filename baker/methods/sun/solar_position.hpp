// The sun's position and the Earth-Sun distance: the Astronomical Almanac's low-precision algorithm as
// Michalsky (1988, "The Astronomical Almanac's algorithm for approximate solar position (1950-2050)", Solar
// Energy 40(3)) gives it: mean longitude and anomaly, ecliptic longitude, obliquity, right ascension and
// declination, Greenwich mean sidereal time. Stated accuracy: 0.01 degrees in right ascension and
// declination for 1950-2050 (UT is used for terrestrial time; the difference, about a minute, is within
// that). Geocentric and without refraction: the sun's true direction (docs/gis.md, "Sunlight over time").
#pragma once

namespace hfbake::sun {

// Julian date of a UTC civil date and time (proleptic Gregorian calendar).
double julian_date(int year, int month, int day, double hours_utc);

// Whether year-month-day is a calendar date.
bool valid_date(int year, int month, int day);

struct SolarPosition {
  double elevation = 0;    // radians above the astronomical horizon, geometric (no refraction)
  double azimuth = 0;      // radians clockwise from true north
  double declination = 0;  // radians
  double distance_au = 1;  // Earth-Sun distance, astronomical units
};

// The sun seen from latitude / longitude (degrees; east and north positive) at Julian date jd (UT).
SolarPosition solar_position(double jd, double latitude_deg, double longitude_deg);

}  // namespace hfbake::sun
