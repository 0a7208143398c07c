#include "field/nodata.hpp"

#include <cmath>

namespace hfbake {
namespace {

bool missing(float z, std::optional<float> nodata_value) {
  return !std::isfinite(z) || (nodata_value && z == *nodata_value);
}

}  // namespace

NodataScan scan_nodata(const HeightField& f, std::optional<float> nodata_value) {
  NodataScan scan;
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i)
      if (missing(f.z[f.index(i, j)], nodata_value)) {
        if (scan.count++ == 0) {
          scan.first_i = i;
          scan.first_j = j;
        }
      }
  return scan;
}

bool fill_nodata(HeightField& f, std::optional<float> nodata_value) {
  std::vector<unsigned char> valid(f.texel_count());
  std::vector<int> frontier, next;
  std::size_t valid_count = 0;
  for (std::size_t k = 0; k < valid.size(); ++k) {
    valid[k] = !missing(f.z[k], nodata_value);
    valid_count += valid[k];
  }
  if (valid_count == 0) return false;
  if (valid_count == valid.size()) return true;

  auto neighbours = [&](int i, int j, auto&& visit) {
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        if (!di && !dj) continue;
        const int ni = i + di, nj = j + dj;
        if (ni < 0 || nj < 0 || ni >= f.width || nj >= f.height) continue;
        visit(ni, nj);
      }
  };
  // The first wave: missing texels touching a valid one.
  std::vector<unsigned char> queued(valid.size(), 0);
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      if (valid[f.index(i, j)]) continue;
      bool touches = false;
      neighbours(i, j, [&](int ni, int nj) { touches |= valid[f.index(ni, nj)] != 0; });
      if (touches) {
        frontier.push_back(int(f.index(i, j)));
        queued[f.index(i, j)] = 1;
      }
    }
  while (!frontier.empty()) {
    // Every texel of a wave reads only texels valid before the wave: the result does not depend on order.
    std::vector<float> values(frontier.size());
    for (std::size_t n = 0; n < frontier.size(); ++n) {
      const int i = frontier[n] % f.width, j = frontier[n] / f.width;
      double sum = 0;
      int count = 0;
      neighbours(i, j, [&](int ni, int nj) {
        if (valid[f.index(ni, nj)]) {
          sum += f.z[f.index(ni, nj)];
          ++count;
        }
      });
      values[n] = float(sum / count);
    }
    next.clear();
    for (std::size_t n = 0; n < frontier.size(); ++n) {
      f.z[std::size_t(frontier[n])] = values[n];
      valid[std::size_t(frontier[n])] = 1;
    }
    for (int k : frontier) {
      neighbours(k % f.width, k / f.width, [&](int ni, int nj) {
        const std::size_t q = f.index(ni, nj);
        if (!valid[q] && !queued[q]) {
          queued[q] = 1;
          next.push_back(int(q));
        }
      });
    }
    frontier.swap(next);
  }
  return true;
}

}  // namespace hfbake
