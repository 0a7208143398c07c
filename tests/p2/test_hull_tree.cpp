// The convex hull tree against the naive march: identical visible sets on real and adversarial lines
// (P2 says the results are identical; this is the proof by test). Also P2's bound t <= 2m + n.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "field/procedural.hpp"
#include "methods/p2/hull_tree.hpp"
#include "methods/p2/naive_visibility.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake {
namespace {

struct LineCheck {
  std::uint64_t receivers = 0, horizons = 0, visible = 0, iterations = 0;
};

// Checks every receiver of the line; returns totals. Fails the test with the first difference.
// x (optional): the samples' positions, pushed with push_at (empty: unit spacing, push).
LineCheck check_line(const std::vector<double>& h, const std::string& what,
                     const std::vector<double>& x = {}) {
  LineCheck c;
  HullTree tree;
  tree.reset(int(h.size()));
  std::vector<int> naive, from_tree, run_starts;
  std::vector<VisibleStretch> stretches;
  const double* xs = x.empty() ? nullptr : x.data();
  for (int r = 0; r < int(h.size()); ++r) {
    if (xs)
      tree.push_at(x[r], h[r]);
    else
      tree.push(h[r]);
    naive_visible(h.data(), r, naive, -1, xs);
    const auto hz = tree.horizons();
    // Horizons strictly increasing, each one visible, and every start of a visible run among them.
    for (std::size_t k = 1; k < hz.size(); ++k) EXPECT_LT(hz[k - 1], hz[k]) << what << " r=" << r;
    run_starts.clear();
    for (std::size_t a = 0; a < naive.size(); ++a)
      if (a == 0 || naive[a - 1] != naive[a] - 1) run_starts.push_back(naive[a]);
    for (int x : hz)
      EXPECT_TRUE(std::binary_search(naive.begin(), naive.end(), x))
          << what << " r=" << r << " horizon " << x;
    for (int x : run_starts)
      EXPECT_TRUE(std::find(hz.begin(), hz.end(), x) != hz.end()) << what << " r=" << r << " run start " << x;
    // The stretches walked from the horizons are exactly the naive visible set.
    visible_stretches(h.data(), r, hz, stretches, xs);
    from_tree.clear();
    for (const auto& s : stretches)
      for (int j = s.first; j <= s.last; ++j) from_tree.push_back(j);
    if (from_tree != naive) {
      ADD_FAILURE() << what << ": visible sets differ at receiver " << r;
      return c;
    }
    c.receivers += 1;
    c.horizons += hz.size();
    c.visible += naive.size();
  }
  c.iterations = tree.iterations();
  // P2 §6: t <= 2m + n.
  EXPECT_LE(c.iterations, 2 * c.horizons + h.size()) << what;
  return c;
}

std::uint64_t lcg(std::uint64_t& s) {
  s = s * 6364136223846793005ull + 1442695040888963407ull;
  return s >> 33;
}

TEST(HullTree, TinyLinesByHand) {
  // A peak hides the valley behind it: from r = 4, p3 (slope 0), p2 (hidden), p1 peak (slope 4/3 > 0).
  std::vector<double> h = {0, 5, 1, 1, 1};
  HullTree t;
  t.reset(5);
  for (double x : h) t.push(x);
  ASSERT_EQ(t.horizons().size(), 2u);
  EXPECT_EQ(t.horizons()[0], 1);
  EXPECT_EQ(t.horizons()[1], 3);
  // Plateau: only the nearest sample is visible (the rest graze it).
  std::vector<int> v;
  std::vector<double> flat(6, 2.0);
  naive_visible(flat.data(), 5, v);
  EXPECT_EQ(v, std::vector<int>{4});
  check_line(h, "tiny");
  check_line(flat, "flat");
}

TEST(HullTree, ProceduralFieldLinesMatchNaive) {
  const int N = 160;
  for (auto kind :
       {ProceduralKind::fractal, ProceduralKind::bricks, ProceduralKind::sines, ProceduralKind::blocks}) {
    ProceduralSpec spec;
    spec.kind = kind;
    spec.width = N;
    spec.height = N;
    spec.seed = 3;
    for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
      const HeightField f = make_procedural(spec, 1.0, wrap);
      LineCheck total;
      // Lines of the sweep driver in several directions (axis, diagonal, oblique), every 7th line.
      for (int K : {16, 7}) {
        SweepSpec ss;
        ss.directions = K;
        for (int k = 0; k < K; k += (K == 16 ? 3 : 2)) {
          const SweepDirection d = plan_direction(f, ss, k);
          std::vector<float> z(d.count);
          for (int l = d.line_begin; l < d.line_end; l += 7) {
            int ib, ie;
            sample_line(f, d, l, z.data(), &ib, &ie);
            std::vector<double> h(z.begin() + ib, z.begin() + ie);
            const auto c = check_line(h, std::string(procedural_kind_name(kind)) + " k=" + std::to_string(k) +
                                             "/" + std::to_string(K) + " line " + std::to_string(l));
            total.receivers += c.receivers;
            total.horizons += c.horizons;
            total.visible += c.visible;
          }
        }
      }
      EXPECT_GT(total.receivers, 1000u);
      // Horizons are at most as many as visible samples (P2: "at least as compact").
      EXPECT_LE(total.horizons, total.visible);
    }
  }
}

TEST(HullTree, RandomLinesMatchNaive) {
  std::uint64_t s = 12345;
  for (int t = 0; t < 60; ++t) {
    const int n = 50 + int(lcg(s) % 300);
    std::vector<double> h(n);
    const int mode = t % 4;
    for (int i = 0; i < n; ++i) {
      if (mode == 0) h[i] = double(lcg(s) % 1000000) / 1000.0;       // continuous-ish
      if (mode == 1) h[i] = double(lcg(s) % 3);                      // 3 levels: ties everywhere
      if (mode == 2) h[i] = double(int(lcg(s) % 11) - 5) + 0.5 * i;  // integer noise on a slope
      if (mode == 3) h[i] = float(std::sin(i * 0.37) * 20 + double(lcg(s) % 100) / 50.0);
    }
    check_line(h, "random mode " + std::to_string(mode) + " #" + std::to_string(t));
  }
}

TEST(HullTree, FractalDetailLinesMatchNaive) {
  // P2 §6 "increasing detail": midpoint displacement with halving range, as in Figure 8.
  std::uint64_t s = 99;
  for (int t = 0; t < 8; ++t) {
    const int levels = 9;
    const int n = (1 << levels) + 1;
    std::vector<double> h(n, 0.0);
    double range = 256;
    for (int step = n - 1; step > 1; step /= 2, range /= 2)
      for (int i = step / 2; i < n; i += step)
        h[i] = 0.5 * (h[i - step / 2] + h[i + step / 2]) + (double(lcg(s) % 2001) / 1000.0 - 1.0) * range;
    check_line(h, "midpoint #" + std::to_string(t));
  }
}

TEST(HullTree, AdversarialLinesMatchNaive) {
  const int n = 301;
  auto make = [&](auto fn) {
    std::vector<double> h(n);
    for (int i = 0; i < n; ++i) h[i] = fn(i);
    return h;
  };
  const double c = 150;
  // Bowls with every other point depressed (P2's O(n^2) worst case), several depths, exact integers.
  for (int depth : {1, 5, 100}) {
    const auto h = make([&](int i) { return (i - c) * (i - c) - ((i % 2) ? depth : 0); });
    const auto r = check_line(h, "bowl depth " + std::to_string(depth));
    EXPECT_GT(r.horizons, 0u);
  }
  check_line(make([&](int i) { return (i - c) * (i - c); }), "smooth bowl");
  check_line(make([&](int i) { return -(i - c) * (i - c); }), "dome");
  check_line(make([&](int i) { return -(i - c) * (i - c) + ((i % 2) ? 7 : 0); }), "spiky dome");
  check_line(make([&](int) { return 3.0; }), "plateau");
  check_line(make([&](int i) { return double((i / 10) % 4); }), "plateaus at 4 levels");
  check_line(make([&](int i) { return double(i / 10); }), "staircase up");
  check_line(make([&](int i) { return double(-(i / 10)); }), "staircase down");
  check_line(make([&](int i) { return 2.0 * i; }), "collinear rising");
  check_line(make([&](int i) { return -3.0 * i; }), "collinear falling");
  // Sawtooth whose peaks are collinear (every 5th sample on the line h = i): exact ties between peaks.
  check_line(make([&](int i) { return i % 5 == 0 ? double(i) : double(i - 7); }), "collinear peaks");
  // Triangle waves: collinear runs on both flanks, shared apexes.
  check_line(make([&](int i) { return double(std::abs(i % 20 - 10)); }), "triangle wave");
  check_line(make([&](int i) { return double(std::abs(i % 20 - 10)) + 0.25 * i; }), "tilted triangle wave");
  // Comb: alternate tall and low spikes.
  check_line(make([&](int i) { return (i % 2) ? 10.0 : (i % 4 == 0 ? 0.0 : 5.0); }), "comb");
  // A V and an inverted V of integer slopes (receivers on the flanks see exact collinear points).
  check_line(make([&](int i) { return std::abs(i - c); }), "V");
  check_line(make([&](int i) { return -std::abs(i - c); }), "inverted V");
  // Tiny lines of every length.
  for (int m = 1; m <= 4; ++m) check_line(std::vector<double>(m, 1.0), "tiny flat");
}

// Receivers beyond the terrain (clamp lines after the border): query() against the naive march over
// the terrain samples only.
TEST(HullTree, QueryBeyondTheTerrainMatchesNaive) {
  std::uint64_t s = 77;
  std::vector<int> hz, naive, a, b;
  for (int t = 0; t < 200; ++t) {
    const int T = 1 + int(lcg(s) % 120);
    std::vector<double> h(T + 40);
    for (auto& x : h) x = (t % 2) ? double(lcg(s) % 5) : double(lcg(s) % 10000) / 100.0;
    HullTree tree;
    tree.reset(T);
    for (int i = 0; i < T; ++i) tree.push(h[i]);
    for (int q = T; q < T + 40; q += 1 + int(lcg(s) % 7)) {
      tree.query(q, h[q], hz);
      naive_visible(h.data(), q, naive, T);
      for (std::size_t k = 1; k < hz.size(); ++k) ASSERT_LT(hz[k - 1], hz[k]);
      // run starts of both
      a.clear();
      for (int c : hz)
        if (c == 0 || !(visibility_slope(h.data(), c - 1, q) > visibility_slope(h.data(), c, q)))
          a.push_back(c);
      b.clear();
      for (std::size_t k = 0; k < naive.size(); ++k)
        if (k == 0 || naive[k - 1] != naive[k] - 1) b.push_back(naive[k]);
      ASSERT_EQ(a, b) << "case " << t << " T " << T << " q " << q;
    }
    // Queries leave the tree as it was: the next push behaves as without them.
    HullTree fresh;
    fresh.reset(T + 1);
    for (int i = 0; i <= T; ++i) fresh.push(h[i]);
    tree.reset(T + 1);
    for (int i = 0; i < T; ++i) tree.push(h[i]);
    tree.query(T + 3, 1.0, hz);
    tree.push(h[T]);
    ASSERT_TRUE(std::equal(tree.horizons().begin(), tree.horizons().end(), fresh.horizons().begin(),
                           fresh.horizons().end()));
  }
}

// Samples at any increasing positions (P2's exact line profiles: the columns and the row and diagonal
// crossings between them, push_at): the tree against the naive march with the same positions.
TEST(HullTree, LinesAtAnyPositionsMatchNaive) {
  std::uint64_t s = 4242;
  for (int t = 0; t < 80; ++t) {
    const int n = 40 + int(lcg(s) % 300);
    std::vector<double> x(n), h(n);
    const int mode = t % 5;
    double at = 0;
    for (int i = 0; i < n; ++i) {
      // Gaps: dyadic (exact ties possible), or continuous down to 1e-6 (a crossing next to a column).
      const double gap =
          mode < 3 ? 0.25 * double(1 + lcg(s) % 4) : std::pow(10.0, -6.0 * double(lcg(s) % 1000) / 1000);
      at += i == 0 ? 0 : gap;
      x[i] = at;
      if (mode == 0) h[i] = double(lcg(s) % 3);                               // 3 levels: ties everywhere
      if (mode == 1) h[i] = 2 * x[i];                                         // collinear, exact
      if (mode == 2) h[i] = 2.5 * std::floor(x[i] / 3) - 0.5 * (lcg(s) % 2);  // steps
      if (mode == 3) h[i] = double(lcg(s) % 1000000) / 1000.0;
      if (mode == 4) h[i] = float(std::sin(x[i] * 0.37) * 20);  // smooth, float heights
    }
    check_line(h, "positions mode " + std::to_string(mode) + " #" + std::to_string(t), x);
  }
  // The unit positions as push_at: the same horizons as push.
  std::vector<double> h(200), x(200);
  for (int i = 0; i < 200; ++i) h[i] = double(lcg(s) % 7), x[i] = i;
  HullTree a, b;
  a.reset(200), b.reset(200);
  for (int i = 0; i < 200; ++i) {
    a.push(h[i]), b.push_at(x[i], h[i]);
    ASSERT_TRUE(
        std::equal(a.horizons().begin(), a.horizons().end(), b.horizons().begin(), b.horizons().end()));
  }
  // Queries beyond the terrain at a position.
  std::vector<int> hz, naive;
  for (int t = 0; t < 100; ++t) {
    const int T = 1 + int(lcg(s) % 100);
    std::vector<double> hx(T + 1), xx(T + 1);
    for (int i = 0; i <= T; ++i)
      xx[i] = (i ? xx[i - 1] : 0) + 0.25 * double(1 + lcg(s) % 4), hx[i] = double(lcg(s) % 4);
    HullTree tree;
    tree.reset(T);
    for (int i = 0; i < T; ++i) tree.push_at(xx[i], hx[i]);
    tree.query(xx[T], hx[T], hz);
    naive_visible(hx.data(), T, naive, T, xx.data());
    std::vector<int> a2, b2;
    for (int c : hz)
      if (c == 0 ||
          !(visibility_slope(hx.data(), xx.data(), c - 1, T) > visibility_slope(hx.data(), xx.data(), c, T)))
        a2.push_back(c);
    for (std::size_t k = 0; k < naive.size(); ++k)
      if (k == 0 || naive[k - 1] != naive[k] - 1) b2.push_back(naive[k]);
    ASSERT_EQ(a2, b2) << "case " << t;
  }
}

TEST(HullTree, ReusedTreeGivesTheSameResult) {
  std::uint64_t s = 7;
  std::vector<double> a(200), b(120);
  for (auto& x : a) x = double(lcg(s) % 50);
  for (auto& x : b) x = double(lcg(s) % 50);
  HullTree t1, t2;
  t1.reset(200);
  for (double x : a) t1.push(x);
  t1.reset(120);
  t2.reset(120);
  for (std::size_t i = 0; i < b.size(); ++i) {
    t1.push(b[i]);
    t2.push(b[i]);
    ASSERT_TRUE(
        std::equal(t1.horizons().begin(), t1.horizons().end(), t2.horizons().begin(), t2.horizons().end()));
  }
  EXPECT_EQ(t1.iterations(), t2.iterations());
}

}  // namespace
}  // namespace hfbake
