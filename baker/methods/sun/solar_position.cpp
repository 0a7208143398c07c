#include "methods/sun/solar_position.hpp"

#include <cmath>

#include "core/vec.hpp"

namespace hfbake::sun {

namespace {

constexpr double kRad = kPi / 180;

// x modulo m, in [0, m).
double wrap(double x, double m) {
  const double r = std::fmod(x, m);
  return r < 0 ? r + m : r;
}

// Days from 1970-01-01 to year-month-day (proleptic Gregorian; the era arithmetic of the civil calendar).
long days_from_civil(int y, int m, int d) {
  y -= m <= 2 ? 1 : 0;
  const long era = (y >= 0 ? y : y - 399) / 400;
  const long yoe = long(y) - era * 400;
  const long doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const long doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

}  // namespace

bool valid_date(int year, int month, int day) {
  if (month < 1 || month > 12 || day < 1) return false;
  static const int days[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
  return day <= days[month - 1] + (month == 2 && leap ? 1 : 0);
}

double julian_date(int year, int month, int day, double hours_utc) {
  // 1970-01-01T00:00 UT is JD 2440587.5.
  return 2440587.5 + double(days_from_civil(year, month, day)) + hours_utc / 24;
}

SolarPosition solar_position(double jd, double latitude_deg, double longitude_deg) {
  const double n = jd - 2451545.0;  // days from J2000.0
  // Mean longitude and mean anomaly (degrees), ecliptic longitude, obliquity of the ecliptic.
  const double L = wrap(280.460 + 0.9856474 * n, 360);
  const double g = wrap(357.528 + 0.9856003 * n, 360) * kRad;
  const double lambda = wrap(L + 1.915 * std::sin(g) + 0.020 * std::sin(2 * g), 360) * kRad;
  const double eps = (23.439 - 0.0000004 * n) * kRad;
  const double ra = std::atan2(std::cos(eps) * std::sin(lambda), std::cos(lambda));
  const double dec = std::asin(std::sin(eps) * std::sin(lambda));
  // Greenwich and local mean sidereal time (hours); n includes the time of day, so the hours of the day
  // enter through both terms (together the sidereal rate 1.0027379 per hour).
  const double hours = wrap(jd - 0.5, 1.0) * 24;
  const double gmst = wrap(6.697375 + 0.0657098242 * n + hours, 24);
  const double lmst = wrap(gmst + longitude_deg / 15, 24);
  double ha = lmst * 15 * kRad - ra;  // hour angle, positive west of the meridian
  ha = wrap(ha + kPi, 2 * kPi) - kPi;
  const double lat = latitude_deg * kRad;
  SolarPosition p;
  p.declination = dec;
  const double se = std::sin(dec) * std::sin(lat) + std::cos(dec) * std::cos(lat) * std::cos(ha);
  p.elevation = std::asin(se < -1 ? -1 : (se > 1 ? 1 : se));
  p.azimuth = wrap(std::atan2(-std::cos(dec) * std::sin(ha),
                              std::cos(lat) * std::sin(dec) - std::sin(lat) * std::cos(dec) * std::cos(ha)),
                   2 * kPi);
  p.distance_au = 1.00014 - 0.01671 * std::cos(g) - 0.00014 * std::cos(2 * g);
  return p;
}

}  // namespace hfbake::sun
