// Chart packing throughput and efficiency (uv/bitimage_packer.h) on synthetic
// chart-like shapes: rectangles, L shapes and triangles with log-uniform
// sizes, half of them turned by arbitrary angles. Prints one line per run:
// shape count, size range, padding, atlas side, efficiency (covered texels /
// atlas texels), the same at the lower bound on the side, and the time.
//
//   bench_uv_pack [--count N] [--min-size S] [--max-size S] [--padding P]
//                 [--seed K] [--side W] [--repeats R] [--aspect A]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <vector>

#include "uv/bitimage_packer.h"

namespace {

using luxel::Vec2;
using luxel::uv::PackShape;

void triangle(PackShape* s, double ax, double ay, double bx, double by, double cx, double cy) {
  s->corners.push_back({static_cast<float>(ax), static_cast<float>(ay)});
  s->corners.push_back({static_cast<float>(bx), static_cast<float>(by)});
  s->corners.push_back({static_cast<float>(cx), static_cast<float>(cy)});
}

void rect(PackShape* s, double x, double y, double w, double h) {
  triangle(s, x, y, x + w, y, x + w, y + h);
  triangle(s, x, y, x + w, y + h, x, y + h);
}

std::vector<PackShape> make_shapes(unsigned seed, int count, double min_size, double max_size,
                                   double min_aspect) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<PackShape> shapes;
  const double lmin = std::log(min_size), lmax = std::log(max_size);
  for (int i = 0; i < count; ++i) {
    const double a = std::exp(lmin + u(rng) * (lmax - lmin));
    const double b = a * (min_aspect + (1 - min_aspect) * u(rng));
    PackShape s;
    const double kind = u(rng);
    if (kind < 0.5) {
      rect(&s, 0, 0, a, b);
    } else if (kind < 0.75) {
      rect(&s, 0, 0, a, b * 0.4);
      rect(&s, 0, b * 0.4, a * 0.4, b * 0.6);
    } else {
      triangle(&s, 0, 0, a, 0, a * u(rng), b);
    }
    const double angle = u(rng) < 0.5 ? 0 : u(rng) * 6.283185307179586;
    const double c = std::cos(angle), sn = std::sin(angle);
    for (Vec2& p : s.corners) {
      const double x = p.x, y = p.y;
      p = {static_cast<float>(c * x - sn * y), static_cast<float>(sn * x + c * y)};
    }
    shapes.push_back(std::move(s));
  }
  return shapes;
}

}  // namespace

int main(int argc, char** argv) {
  int count = 20000, padding = 2, side = 0, repeats = 1;
  unsigned seed = 1;
  double min_size = 2, max_size = 64, aspect = 0.3;
  for (int i = 1; i + 1 < argc; i += 2) {
    const char* k = argv[i];
    const char* v = argv[i + 1];
    if (!std::strcmp(k, "--count"))
      count = std::atoi(v);
    else if (!std::strcmp(k, "--padding"))
      padding = std::atoi(v);
    else if (!std::strcmp(k, "--side"))
      side = std::atoi(v);
    else if (!std::strcmp(k, "--repeats"))
      repeats = std::atoi(v);
    else if (!std::strcmp(k, "--seed"))
      seed = static_cast<unsigned>(std::atoi(v));
    else if (!std::strcmp(k, "--min-size"))
      min_size = std::atof(v);
    else if (!std::strcmp(k, "--max-size"))
      max_size = std::atof(v);
    else if (!std::strcmp(k, "--aspect"))
      aspect = std::atof(v);
    else {
      std::fprintf(stderr, "unknown option %s\n", k);
      return 2;
    }
  }
  const auto shapes = make_shapes(seed, count, min_size, max_size, aspect);
  luxel::uv::PackOptions o;
  o.padding_texels = padding;
  o.width = o.height = side;
  double best = 1e30;
  luxel::Result<luxel::uv::PackResult> r = luxel::internal_error("not run");
  for (int i = 0; i < repeats; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    r = luxel::uv::pack_shapes(shapes, o);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    best = std::min(best, s);
    if (!r) {
      std::fprintf(stderr, "%s\n", r.status().to_string().c_str());
      return 1;
    }
  }
  std::printf(
      "shapes %d  sizes %.0f-%.0f  padding %d  atlas %d x %d  attempts %d  "
      "efficiency %.1f %%  footprint/atlas %.1f %%  time %.3f s\n",
      count, min_size, max_size, padding, r->width, r->height, r->attempts, 100 * r->efficiency,
      100.0 * r->footprint_texels / (static_cast<double>(r->width) * r->height), best);
  return 0;
}
