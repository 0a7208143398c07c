// hfbake horizon end to end: one-line errors (exit 2), the profile of a synthetic DEM against GRASS
// r.horizon's point mode (skipped when grass is absent), a geographic (EPSG:4326) DEM against PROJ's
// geodesics, and the real lidar tile in its CRS and warped to EPSG:4326 (skipped when absent).
#include <fcntl.h>
#include <gdal_priv.h>
#include <geodesic.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../cli/run_hfbake.hpp"

namespace {
namespace fs = std::filesystem;
using hfbake::cli_test::run_hfbake;

constexpr double kPi = 3.14159265358979323846, kDeg = 180 / kPi;

struct Row {
  double azimuth = 0, elevation = 0, distance = 0, x = 0, y = 0, z = 0;
  bool found = false;
};

fs::path temp_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("hfbake_horizon_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// A float32 GeoTIFF of w x h texels, z(i, j), with geotransform g and the CRS EPSG:epsg.
void write_dem(const fs::path& file, int w, int h, const std::array<double, 6>& g, int epsg,
               const std::function<double(int, int)>& z, std::optional<double> nodata = std::nullopt) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  std::unique_ptr<GDALDataset> ds(driver->Create(file.c_str(), w, h, 1, GDT_Float32, nullptr));
  ASSERT_TRUE(ds);
  double gt[6] = {g[0], g[1], g[2], g[3], g[4], g[5]};
  ds->SetGeoTransform(gt);
  OGRSpatialReference srs;
  srs.importFromEPSG(epsg);
  ds->SetSpatialRef(&srs);
  std::vector<float> v(std::size_t(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) v[std::size_t(j) * w + i] = float(z(i, j));
  GDALRasterBand* band = ds->GetRasterBand(1);
  if (nodata) band->SetNoDataValue(*nodata);
  ASSERT_EQ(band->RasterIO(GF_Write, 0, 0, w, h, v.data(), w, h, GDT_Float32, 0, 0, nullptr), CE_None);
}

// hfbake horizon ARGS --out FILE, its CSV rows.
std::vector<Row> horizon(const fs::path& dir, const std::string& args) {
  const fs::path out = dir / "horizon.csv";
  fs::remove(out);
  const auto r = run_hfbake(dir, "horizon " + args + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(out);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "azimuth_deg,elevation_deg,distance,caster_x,caster_y,caster_z");
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    Row row;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream s(line);
    s >> row.azimuth;
    row.found = bool(s >> row.elevation >> row.distance >> row.x >> row.y >> row.z);
    rows.push_back(row);
  }
  return rows;
}

bool have(const char* program) {
  return std::system((std::string("command -v ") + program + " >/dev/null 2>&1").c_str()) == 0;
}

TEST(HorizonCli, BadInputIsOneLineAndExit2) {
  const fs::path dir = temp_dir("errors");
  const fs::path dem = dir / "dem.tif";
  write_dem(
      dem, 20, 10, {1000, 2, 0, 2000, 0, -2}, 32633,
      [](int i, int j) { return i == 5 && j == 5 ? -9999.0 : 1.0 * i; }, -9999.0);
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"--at 1000,2000",
       "--at: 1000,2000 is outside the surface: its texel centres span x 1001..1039, y 1981..1999"},
      {"--at 1000.99999999999,1990",  // within 10 digits of the range's edge: not printed on it
       "--at: 1000.99999999999,1990 is outside the surface: its texel centres span x 1001..1039, y "
       "1981..1999"},
      {"--at 1011,1989", "--at: 1011,1989 is on NoData"},
      {"--at 1011", "--at: is \"1011\", not X,Y"},
      {"--at 1021,1981 --directions 0", "--directions: must be in [1, 1000000]"},
      {"--at 1021,1981 --format xml", "--format: is xml, not csv or json"},
      {"--at 1021,1981 --plot x.png --plot-size 10", "--plot-size: must be in [64, 8192]"},
      {"--at 1021,1981 --band 1", "--band: is 1 but the raster has 1 band(s)"},
      {"--at 1021,1981 --refraction 0.2", "--refraction: applies with Earth curvature only"},
      {"--at 15,46 --lonlat", "--at: "},
      {"--at 200,46 --lonlat", "--at: longitude 200 is outside [-180, 180]"},
      {"--at 15,95 --lonlat", "--at: latitude 95 is outside [-90, 90]"},
  };
  for (const Case& c : cases) {
    const auto r = run_hfbake(dir, "horizon " + dem.string() + " " + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args;
    ASSERT_EQ(r.error_lines().size(), 1u) << c.args << ": " << r.err;
    EXPECT_NE(r.error_lines()[0].find("hfbake: error: " + dem.string() + ": " + c.expect), std::string::npos)
        << r.error_lines()[0];
  }
  // An empty --out or --plot (an unset shell variable) is refused, not standard output or no plot.
  for (const char* option : {"--out", "--plot"}) {
    const auto e = run_hfbake(dir, "horizon " + dem.string() + " --at 1021,1981 " + option + " ''");
    EXPECT_EQ(e.exit_code, 2) << option;
    EXPECT_NE(e.err.find(std::string("command line: ") + option + ": is empty: name the file"),
              std::string::npos)
        << e.err;
  }
  const auto r = run_hfbake(dir, "horizon " + (dir / "none.tif").string() + " --at 1,1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("none.tif: no such file"), std::string::npos) << r.err;
  // A pipe at the DEM's name is named for what it is, and never opened (no writer: an open would block).
  const fs::path pipe = dir / "pipe.tif";
  ASSERT_EQ(mkfifo(pipe.c_str(), 0600), 0);
  const auto rp = run_hfbake(dir, "horizon " + pipe.string() + " --at 1,1");
  EXPECT_EQ(rp.exit_code, 2);
  EXPECT_NE(rp.err.find("pipe.tif: not a regular file"), std::string::npos) << rp.err;
  fs::remove_all(dir);
}

// The outputs never replace the DEM or each other, and are written whole or not at all: a write the disk
// refuses (a file size limit, SIGXFSZ ignored: EFBIG, as on a full disk) keeps the previous file.
TEST(HorizonCli, OutputsNeverReplaceTheDemAndAreWrittenWhole) {
  const fs::path dir = temp_dir("outputs");
  const fs::path dem = dir / "dem.tif";
  write_dem(dem, 20, 10, {1000, 2, 0, 2000, 0, -2}, 32633, [](int i, int) { return 1.0 * i; });
  const auto bytes = [](const fs::path& f) {
    std::ifstream in(f, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string genuine = bytes(dem), at = "horizon " + dem.string() + " --at 1021,1981 ";
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"--out " + dem.string(), "--out: is the DEM this command reads"},
      {"--plot " + (dir / "." / "dem.tif").string(), "--plot: is the DEM this command reads"},
      {"--out " + (dir / "a").string() + " --plot " + (dir / "a").string(), "--plot: is the --out file too"},
  };
  // An existing folder as --out: refused naming it a folder, nothing written in it.
  fs::create_directory(dir / "folder");
  const auto folder = run_hfbake(dir, at + "--out " + (dir / "folder").string() + "/");
  EXPECT_EQ(folder.exit_code, 2) << folder.err;
  ASSERT_EQ(folder.error_lines().size(), 1u) << folder.err;
  EXPECT_NE(folder.err.find("--out: is a folder: name the file to write"), std::string::npos) << folder.err;
  EXPECT_TRUE(fs::is_empty(dir / "folder"));
  // Under a file: refused before anything is computed. Into folders not made yet: written, the folders made.
  const auto under = run_hfbake(dir, at + "--out " + (dem / "x.csv").string());
  EXPECT_EQ(under.exit_code, 2) << under.err;
  ASSERT_EQ(under.error_lines().size(), 1u) << under.err;
  EXPECT_NE(under.err.find("--out: " + dem.string() + " is not a folder"), std::string::npos) << under.err;
  const auto deep = run_hfbake(dir, at + "--out " + (dir / "p" / "q" / "h.csv").string());
  EXPECT_EQ(deep.exit_code, 0) << deep.err;
  EXPECT_EQ(bytes(dir / "p" / "q" / "h.csv").rfind("azimuth_deg,elevation_deg", 0), 0u);
  for (const Case& c : cases) {
    const auto r = run_hfbake(dir, at + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args;
    ASSERT_EQ(r.error_lines().size(), 1u) << c.args << ": " << r.err;
    EXPECT_NE(r.error_lines()[0].find(dem.string() + ": " + c.expect), std::string::npos)
        << r.error_lines()[0];
    EXPECT_EQ(bytes(dem), genuine);
    EXPECT_FALSE(fs::exists(dir / "a"));
  }
  std::ofstream(dir / "plot.png") << "keep";
  struct rlimit limit {};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &limit), 0);
  const rlim_t soft = limit.rlim_cur;
  const auto previous = std::signal(SIGXFSZ, SIG_IGN);
  limit.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  const auto r = run_hfbake(dir, at + "--plot " + (dir / "plot.png").string() + " --plot-size 2048");
  limit.rlim_cur = soft;
  setrlimit(RLIMIT_FSIZE, &limit);
  std::signal(SIGXFSZ, previous);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(bytes(dir / "plot.png"), "keep");
  // A FIFO, and a link to one (as /dev/stdout is a link to a stream), receive the CSV and stay what they
  // are: a rename would have put a file in their place and the reader would get nothing.
  ASSERT_EQ(mkfifo((dir / "fifo").c_str(), 0600), 0);
  fs::create_symlink(dir / "fifo", dir / "link");
  for (const char* name : {"fifo", "link"}) {
    SCOPED_TRACE(name);
    std::string got;
    std::thread reader([&] {
      std::ifstream in(dir / "fifo", std::ios::binary);
      got.assign(std::istreambuf_iterator<char>(in), {});
    });
    const auto w = run_hfbake(dir, at + "--out " + (dir / name).string());
    // A command that never opened the FIFO leaves the reader waiting: a writer of nothing ends it.
    if (const int fd = open((dir / "fifo").c_str(), O_WRONLY | O_NONBLOCK); fd >= 0) close(fd);
    reader.join();
    EXPECT_EQ(w.exit_code, 0) << w.err;
    EXPECT_EQ(got.rfind("azimuth_deg,elevation_deg", 0), 0u) << got;
    EXPECT_TRUE(fs::is_fifo(fs::symlink_status(dir / "fifo")));
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / "link")));
  }
  // A link to the process's own standard output (as /dev/stdout is), redirected by the shell to a file,
  // appended to: the CSV goes into that file after what it held, and the link stays a link.
  fs::create_symlink("/proc/self/fd/1", dir / "stdout");
  std::ofstream(dir / "redirected.csv") << "before\n";
  const std::string cmd = std::string(HFBAKE_BINARY) + " " + at + "--out " + (dir / "stdout").string() +
                          " >>" + (dir / "redirected.csv").string() + " 2>" + (dir / "err.txt").string();
  EXPECT_EQ(std::system(cmd.c_str()), 0) << bytes(dir / "err.txt");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / "stdout")));
  EXPECT_EQ(bytes(dir / "redirected.csv").rfind("before\nazimuth_deg,elevation_deg", 0), 0u)
      << bytes(dir / "redirected.csv");
  fs::remove_all(dir);
}

// A bowl with two Gaussian hills on its side, 10 m texels, at UTM 33N's central meridian (no grid
// convergence, so r.horizon's true-north correction is nil). r.horizon (our reading of
// raster/r.horizon/main.c) snaps the point to its cell, steps one cell along the ray, and takes at each step
// the cell whose centre is nearest, at that centre's distance, lowered by d^2 / (2 * 6371000) (no
// refraction): its casters are texel centres up to half a cell diagonal off the ray. Along the axes those
// centres lie on the ray and are vertices of the triangulation, so the two agree to the curvature radius
// (hfbake's is the ellipsoid's, 0.3 % apart: 1e-5°); elsewhere r.horizon's own error is at most the terrain's
// rise over that offset seen from the caster's distance, atan(g s sqrt(1/2) / d) with g the steepest slope, s
// = 10 m. The point is the bottom of the bowl, so that its casters are far (r.horizon's off-ray centres next
// to the point are not).
TEST(HorizonCli, AgreesWithGrassRHorizon) {
  if (!have("grass")) GTEST_SKIP() << "GRASS GIS not installed (apt-get install grass-core)";
  const fs::path dir = temp_dir("grass");
  const fs::path dem = dir / "dem.tif";
  const int n = 201;
  const double s = 10, x0 = 500000 - 100.5 * s, y0 = 5000000 + 100.5 * s;
  auto z = [&](int i, int j) {
    const double x = (i - 100) * s, y = (100 - j) * s;
    return 50 + 1e-4 * (x * x + y * y) +
           150 * std::exp(-((x - 600) * (x - 600) + (y - 500) * (y - 500)) / 1e5) +
           100 * std::exp(-((x + 700) * (x + 700) + (y + 400) * (y + 400)) / 0.6e5);
  };
  write_dem(dem, n, n, {x0, s, 0, y0, 0, -s}, 32633, z);
  const std::string grass_out = (dir / "grass.csv").string();
  const std::string script = "r.in.gdal input=" + dem.string() +
                             " output=dem --quiet && g.region raster=dem && r.horizon -d -c elevation=dem "
                             "coordinates=500000,5000000 step=10 file=" +
                             grass_out;
  const std::string cmd = "cd " + dir.string() + " && grass --tmp-location EPSG:32633 --exec bash -c '" +
                          script + "' >" + (dir / "grass.log").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << "see " << (dir / "grass.log");
  std::map<int, double> grass;  // compass azimuth (degrees) -> elevation (degrees)
  {
    std::ifstream in(grass_out);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      double a = 0, e = 0;
      ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf", &a, &e), 2) << line;
      grass[int(std::lround(a)) % 360] = e;
    }
  }
  ASSERT_EQ(grass.size(), 36u);
  const std::vector<Row> rows =
      horizon(dir, dem.string() + " --at 500000,5000000 --directions 36 --curvature --refraction 0");
  ASSERT_EQ(rows.size(), 36u);
  double g = 0;  // the steepest slope between neighbours
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i)
      g = std::max({g, std::abs(z(i + 1, j) - z(i, j)) / s, std::abs(z(i, j + 1) - z(i, j)) / s});
  double worst_axis = 0, worst = 0;
  for (const Row& r : rows) {
    const int a = int(std::lround(r.azimuth));
    ASSERT_TRUE(r.found && grass.count(a)) << a;
    const double diff = std::abs(r.elevation - grass[a]);
    if (a % 90 == 0) {
      EXPECT_LT(diff, 1e-4) << a;  // r.horizon prints 6 decimals
      worst_axis = std::max(worst_axis, diff);
    } else {
      EXPECT_LT(diff, std::atan(g * s * std::sqrt(0.5) / r.distance) * kDeg + 1e-4)
          << a << " d " << r.distance;
      worst = std::max(worst, diff);
    }
  }
  std::printf("r.horizon vs hfbake: axes %.2e deg, others %.3f deg\n", worst_axis, worst);
  fs::remove_all(dir);
}

// A flat EPSG:4326 DEM (3 arc-second texels, 100 m high) at 46° N with two 300 m walls, a column 100 texels
// (6.4 km) east of the receiver and a row 160 texels (14.8 km) north: for each ray the distance hfbake
// reports to its caster against PROJ's geodesic (geod_inverse on WGS 84) to the same point, the caster's
// elevation against the closed form at the geodesic distance, the ray's azimuth against the geodesic's.
// hfbake's ground frame is the receiver's tangent plane with the ellipsoid's metric scales at the receiver
// (docs/gis.md "Geographic DEMs"); the bounds below are that approximation's, measured here.
// A geographic DEM whose longitudes run past 180 (across the antimeridian, and one of 0..360): --lonlat
// takes the point in [-180, 180] and finds it a whole turn away, the profile that of --at in the raster's own
// longitudes.
TEST(HorizonCli, LonLatReachesADemPastTheAntimeridian) {
  const fs::path dir = temp_dir("antimeridian");
  const double t = 3.0 / 3600;
  const auto z = [](int i, int j) { return 100.0 + 40.0 * std::sin(0.3 * i) * std::cos(0.2 * j); };
  for (const double lon0 : {179.95, 359.95}) {
    SCOPED_TRACE(lon0);
    const fs::path dem = dir / ("dem" + std::to_string(int(lon0)) + ".tif");
    write_dem(dem, 120, 80, {lon0, t, 0, -16.0, 0, -t}, 4326, z);
    const double lon = lon0 + 90.25 * t, lat = -16.0 - 40.25 * t;  // past 180 (or 360) on the raster
    std::ostringstream own, wrapped;
    own.precision(12), wrapped.precision(12);
    own << lon << "," << lat;
    wrapped << std::remainder(lon, 360.0) << "," << lat;
    const std::vector<Row> a = horizon(dir, dem.string() + " --at " + own.str() + " --directions 8");
    const std::vector<Row> b =
        horizon(dir, dem.string() + " --lonlat --at " + wrapped.str() + " --directions 8");
    ASSERT_EQ(a.size(), 8u);
    ASSERT_EQ(b.size(), a.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
      EXPECT_NEAR(b[k].elevation, a[k].elevation, 1e-4) << k;
      EXPECT_NEAR(b[k].x, a[k].x, 1e-6) << k;
    }
  }
  fs::remove_all(dir);
}

TEST(HorizonCli, GeographicDemAgainstGeodesics) {
  const fs::path dir = temp_dir("geographic");
  const fs::path dem = dir / "dem.tif";
  const double t = 3.0 / 3600, lon0 = 14.0, lat1 = 46.2;
  const int n = 401, ri = 200, rj = 200;
  write_dem(dem, n, n, {lon0, t, 0, lat1, 0, -t}, 4326,
            [&](int i, int j) { return (i == 300 || j == 40) ? 300.0 : 100.0; });
  const double lon_r = lon0 + (ri + 0.5) * t, lat_r = lat1 - (rj + 0.5) * t;
  geod_geodesic wgs84;
  geod_init(&wgs84, 6378137, 1 / 298.257223563);
  std::ostringstream at;
  at.precision(12);
  at << lon_r << "," << lat_r;
  const std::vector<Row> rows = horizon(dir, dem.string() + " --at " + at.str() + " --directions 36");
  const double e2 = 0.0066943799901, sl = std::sin(lat_r / kDeg);
  const double M = 6378137 * (1 - e2) / std::pow(1 - e2 * sl * sl, 1.5),
               N = 6378137 / std::sqrt(1 - e2 * sl * sl);
  double worst_d = 0, worst_az = 0, worst_e = 0;
  int checked = 0;
  for (const Row& r : rows) {
    const int a = int(std::lround(r.azimuth));
    if (!(a <= 20 || (a >= 40 && a <= 140))) continue;  // the rays that meet a wall
    ASSERT_TRUE(r.found) << a;
    EXPECT_NEAR(r.z, 300, 1e-3) << a << ": the caster is on a wall";
    double s12 = 0, azi1 = 0, azi2 = 0;
    geod_inverse(&wgs84, lat_r, lon_r, r.y, r.x, &s12, &azi1, &azi2);
    const double k = 0.13, ca = std::cos(r.azimuth / kDeg), sa = std::sin(r.azimuth / kDeg);
    const double R = 1 / (ca * ca / M + sa * sa / N);
    const double expect = std::atan((300 - 100 - (1 - k) * s12 * s12 / (2 * R)) / s12) * kDeg;
    worst_d = std::max(worst_d, std::abs(r.distance / s12 - 1));
    worst_az = std::max(worst_az, std::abs(std::remainder(azi1 - r.azimuth, 360.0)));
    worst_e = std::max(worst_e, std::abs(r.elevation - expect));
    ++checked;
  }
  EXPECT_EQ(checked, 14);
  std::printf(
      "geographic DEM: distances within %.2e of the geodesic's, azimuths %.4f deg, elevations %.5f deg\n",
      worst_d, worst_az, worst_e);
  EXPECT_LT(worst_d, 1e-3);
  EXPECT_LT(worst_az, 0.05);
  EXPECT_LT(worst_e, 0.002);
  fs::remove_all(dir);
}

// The 1 m lidar tile in its projected CRS (D96/TM, with curvature) and warped to EPSG:4326 (gdalwarp,
// bilinear): the same three points (WGS 84 lon/lat), an eye 2 m above the ground, 72 azimuths from true
// north. They differ by the resampling (and the warp's texels, 0.80 x 1.24 m): measured median 0.003-0.006°,
// largest 0.057°.
TEST(HorizonCli, LidarTileProjectedAndGeographicAgree) {
  const fs::path tile = fs::path(HFBAKE_SHARED_DATA_DIR) / "TM1_564_146.tif";
  if (!fs::exists(tile)) GTEST_SKIP() << "no real DEM at " << tile;
  if (!have("gdalwarp")) GTEST_SKIP() << "GDAL's tools not found (apt-get install gdal-bin)";
  const fs::path dir = temp_dir("lidar");
  const fs::path warped = dir / "tm1_4326.tif";
  ASSERT_EQ(std::system(("gdalwarp -q -t_srs EPSG:4326 -r bilinear -dstnodata -9999 " + tile.string() + " " +
                         warped.string())
                            .c_str()),
            0);
  OGRSpatialReference d96, wgs84;
  d96.importFromEPSG(3794);
  wgs84.importFromEPSG(4326);
  d96.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> ct(OGRCreateCoordinateTransformation(&d96, &wgs84));
  ASSERT_TRUE(ct);
  std::vector<double> diffs;
  for (auto [x, y] :
       {std::pair{564500.5, 146500.5}, std::pair{564250.5, 146300.5}, std::pair{564700.5, 146800.5}}) {
    ASSERT_TRUE(ct->Transform(1, &x, &y));
    std::ostringstream at;
    at.precision(15);
    at << x << "," << y << " --lonlat --directions 72 --observer-height 2";
    const std::vector<Row> projected = horizon(dir, tile.string() + " --at " + at.str() + " --curvature");
    const std::vector<Row> geographic = horizon(dir, warped.string() + " --at " + at.str());
    ASSERT_EQ(projected.size(), 72u);
    ASSERT_EQ(geographic.size(), 72u);
    for (std::size_t k = 0; k < 72; ++k) {
      ASSERT_TRUE(projected[k].found && geographic[k].found);
      diffs.push_back(std::abs(projected[k].elevation - geographic[k].elevation));
    }
  }
  std::sort(diffs.begin(), diffs.end());
  std::printf("lidar tile, projected vs EPSG:4326: median %.4f deg, p90 %.4f, max %.4f\n",
              diffs[diffs.size() / 2], diffs[diffs.size() * 9 / 10], diffs.back());
  EXPECT_LT(diffs[diffs.size() / 2], 0.015);
  EXPECT_LT(diffs.back(), 0.1);
  fs::remove_all(dir);
}

// --format json: the same rays as the CSV, with the point, the curvature and the grid convergence.
// A V valley across x whose sides rise 0.5 per ground unit, so that from its floor the horizon east and west
// is atan(0.5) at every distance: stored as Int16 with a declared scale and offset, and as metres on a CRS in
// US survey feet. Without --height-scale / --height-offset the command takes the stored values and warns
// once, naming the file and the arguments; with them it gives the closed form.
TEST(HorizonCli, DeclaredScaleOffsetAndHeightUnitAreWarnedAndApplied) {
  const fs::path dir = temp_dir("declared");
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  const double us_foot = 1200.0 / 3937.0;  // metres
  struct Case {
    const char* name;
    int epsg;
    GDALDataType type;
    double scale, offset, stored_per_unit;  // stored = (height - offset) / scale, heights x stored_per_unit
    const char* unit;
    double x0;  // the floor on the CRS's central meridian, where grid north is true north
    std::string args, warning;
  };
  const Case cases[] = {
      {"scaled.tif", 32633, GDT_Int16, 0.01, 200, 1, "", 500000 - 41,
       "--height-scale 0.01 --height-offset 200",
       "the file declares scale 0.01 and offset 200, not applied (heights are the stored values): "
       "--height-scale 0.01 --height-offset 200 apply them"},
      {"metres_on_feet.tif", 2229, GDT_Float32, 1, 0, us_foot, "m", 6561666.667 - 41,
       "--height-scale " + std::to_string(1 / us_foot),
       "the band's heights are in m and its pixels in US survey foot: elevations come out too low; give "
       "--height-scale 3.28083"}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path dem = dir / c.name;
    {
      const int w = 41, h = 21;
      std::unique_ptr<GDALDataset> ds(driver->Create(dem.c_str(), w, h, 1, c.type, nullptr));
      ASSERT_TRUE(ds);
      double gt[6] = {c.x0, 2, 0, 2000000, 0, -2};
      ds->SetGeoTransform(gt);
      OGRSpatialReference srs;
      srs.importFromEPSG(c.epsg);
      ds->SetSpatialRef(&srs);
      std::vector<double> v(std::size_t(w) * h);
      for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
          v[std::size_t(j) * w + i] =
              ((300 + 0.5 * 2 * std::abs(i - 20)) * c.stored_per_unit - c.offset) / c.scale;
      GDALRasterBand* band = ds->GetRasterBand(1);
      band->SetScale(c.scale);
      band->SetOffset(c.offset);
      band->SetUnitType(c.unit);
      ASSERT_EQ(band->RasterIO(GF_Write, 0, 0, w, h, v.data(), w, h, GDT_Float64, 0, 0, nullptr), CE_None);
    }
    // The floor's centre, 20 texels in.
    const std::string at = " --at " + std::to_string(c.x0 + 41) + ",1999979 --directions 4";
    const auto warned = run_hfbake(dir, "horizon " + dem.string() + at);
    ASSERT_EQ(warned.exit_code, 0) << warned.err;
    EXPECT_EQ(warned.err, "hfbake: warning: " + dem.string() + ": " + c.warning + "\n");
    for (const Row& r : horizon(dir, dem.string() + at)) {
      SCOPED_TRACE(r.azimuth);
      if (r.azimuth == 90 || r.azimuth == 270) {
        EXPECT_GT(std::abs(r.elevation - std::atan(0.5) * kDeg), 1);
      }
    }
    const auto applied = run_hfbake(dir, "horizon " + dem.string() + at + " " + c.args);
    ASSERT_EQ(applied.exit_code, 0) << applied.err;
    EXPECT_EQ(applied.err, "");
    for (const Row& r : horizon(dir, dem.string() + at + " " + c.args)) {
      SCOPED_TRACE(r.azimuth);
      if (r.azimuth == 90 || r.azimuth == 270) {
        ASSERT_TRUE(r.found);
        EXPECT_NEAR(r.elevation, std::atan(0.5) * kDeg, 1e-4);
      }
    }
  }
  EXPECT_NE(
      run_hfbake(dir, "horizon " + (dir / "scaled.tif").string() + " --at 500000,1999979 --height-scale nan")
          .err.find("--height-scale: must be a finite number"),
      std::string::npos);
  fs::remove_all(dir);
}

TEST(HorizonCli, JsonCarriesTheCsvsRays) {
  const fs::path dir = temp_dir("json");
  const fs::path dem = dir / "dem.tif";
  write_dem(dem, 40, 30, {600000, 5, 0, 5100000, 0, -5}, 32633,
            [](int i, int j) { return 0.3 * i + 0.1 * j * j; });
  const std::string args =
      dem.string() + " --at 600100,5099950 --directions 12 --observer-height 1.5 --curvature";
  const std::vector<Row> csv = horizon(dir, args);
  const fs::path out = dir / "horizon.json";
  const fs::path plot = dir / "plot.png";
  ASSERT_EQ(run_hfbake(dir, "horizon " + args + " --format json --out " + out.string() + " --plot " +
                                plot.string() + " --plot-size 128")
                .exit_code,
            0);
  {  // the plot: a 128 x 128 RGB PNG (its pixels are tests/terrain/test_point_horizon's)
    GDALAllRegister();
    std::unique_ptr<GDALDataset> png(GDALDataset::Open(plot.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
    ASSERT_TRUE(png);
    EXPECT_EQ(png->GetRasterXSize(), 128);
    EXPECT_EQ(png->GetRasterYSize(), 128);
    EXPECT_EQ(png->GetRasterCount(), 3);
  }
  std::ifstream in(out);
  const nlohmann::json doc = nlohmann::json::parse(in);
  ASSERT_EQ(doc["rays"].size(), csv.size());
  EXPECT_NEAR(doc["point"]["observer_z"].get<double>() - doc["point"]["surface_z"].get<double>(), 1.5, 1e-9);
  EXPECT_NEAR(doc["curvature"]["refraction"].get<double>(), 0.13, 1e-12);
  // The meridian convergence at the point (UTM 33N, 100 km east of its central meridian: -0.93°),
  // against a step north through OGR's own transforms.
  OGRSpatialReference utm, geo;
  utm.importFromEPSG(32633);
  utm.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  geo.importFromEPSG(4326);
  geo.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> to_geo(OGRCreateCoordinateTransformation(&utm, &geo));
  std::unique_ptr<OGRCoordinateTransformation> to_utm(OGRCreateCoordinateTransformation(&geo, &utm));
  double x = 600100, y = 5099950;
  ASSERT_TRUE(to_geo->Transform(1, &x, &y));
  y += 0.01;
  ASSERT_TRUE(to_utm->Transform(1, &x, &y));
  EXPECT_NEAR(doc["grid_convergence_deg"].get<double>(), std::atan2(x - 600100, y - 5099950) * kDeg, 1e-3);
  for (std::size_t k = 0; k < csv.size(); ++k) {
    const nlohmann::json& ray = doc["rays"][k];
    EXPECT_NEAR(ray["azimuth_deg"].get<double>(), csv[k].azimuth, 1e-6);
    ASSERT_EQ(csv[k].found, !ray["elevation_deg"].is_null()) << k;
    ASSERT_TRUE(ray.contains("found") && ray["found"].is_boolean()) << ray.dump();
    EXPECT_EQ(ray["found"].get<bool>(), csv[k].found) << k;
    if (!csv[k].found) continue;
    EXPECT_NEAR(ray["elevation_deg"].get<double>(), csv[k].elevation, 1e-6);
    EXPECT_NEAR(ray["distance"].get<double>(), csv[k].distance, 1e-4);
    EXPECT_NEAR(ray["caster"][0].get<double>(), csv[k].x, 1e-3);
  }
  fs::remove_all(dir);
}

}  // namespace
