// hsao: horizon-split ambient occlusion (Dimitrov, Bavoil, Sainz, I3D 2008) on a height
// field.
//
// Around the receiver's normal n, N_d directions T_i in the tangent plane (T_0 = the projection of +x, so
// with n = up the directions are the contract's phi_k). Per direction a horizon ray starts along T_i and
// marches N_s steps of R / N_s; whenever the march point Q is below the surface, the ray is deflected towards
// the surface point I above Q (if |I - P| < R and I lies ahead), projected into the (n, T_i) plane (paper
// Fig. 4); when I is beyond R, towards the highest point of the solid column [Q, I] within R (an offline
// refinement: the paper's rule alone stalls on a wall that leaves the sphere and under-occludes with a step
// falloff: 0.293 instead of 0.360 in the pit of the closed-form table). Below the horizon: analytic. Each
// deflection raises the horizon from elevation a to b (measured from the tangent plane); that band is
// occluded by a slab through I parallel to -n, at tangential distance x, and adds 2 * integral_a^b rho(x /
// cos e) sin e cos e de (= H_b^2 - H_a^2 with rho = 1: the paper's Eq. 6, T = H^2). Above the horizon: N_n
// normal rays per direction, stratified in cosine measure over [H_i^2, 1] (the corrected distribution,
// the paper's Sec. 4.1), each marched N_s steps to R and weighing (1 - H_i^2) rho(d) / N_n. On a height
// field with n = up the (n, T) planes are vertical slices without overhangs: every ray above the exact slice
// horizon is open, so the sampled term is zero up to the horizon search's sampling.
// Surface (HsaoSurface): the paper's march samples a depth buffer at N_s steps; on a height
// field the bilinear surface between steps misses the triangulated surface's peaks (rough nightly field:
// +6.9 % too open against the Embree reference). `triangles` (the job's default) tests every ray at every
// vertex of the triangulated surface under its ground track (triangle_profile_span), where ray and surface,
// both linear between vertices, are compared exactly; a deflected horizon ray resumes at the same distance
// from the receiver, and a normal ray's hit is where the surface crosses it on the piece before the first
// vertex above it.
#pragma once

#include <vector>

#include "core/direction_blocks.hpp"
#include "core/run_control.hpp"
#include "core/vec.hpp"
#include "field/height_field.hpp"
#include "job/params.hpp"
#include "methods/ao/falloff.hpp"

namespace hfbake {

// Where the rays are tested against the terrain: at N_s equal steps on the bilinear surface (the paper's
// depth-buffer march), or at every vertex of the reference's triangulated surface under the ray's ground
// track (triangle_profile.hpp: every column, row and diagonal crossing), where the ray and the surface,
// both linear between vertices, are exactly compared.
enum class HsaoSurface { bilinear, triangles };

struct HsaoSettings {
  Falloff falloff;  // step (binary R), linear or smooth; falloff.radius = R (world units)
  int directions = 16;
  HsaoSurface surface = HsaoSurface::bilinear;  // the job's default: triangles (read_hsao_settings)
  int steps = 32;                               // bilinear only
  int normal_rays = 2;
};

struct HsaoTexel {
  double horizon_occlusion = 0;  // O_T
  double normal_occlusion = 0;   // O_N
  Vec3 bent_normal{0, 0, 1};     // unit, cosine weighted by (1 - rho) below the horizons, rays ignored
  double occluded() const { return horizon_occlusion + normal_occlusion; }
};

HsaoTexel hsao_texel(const HeightField& field, Vec3 normal, int i, int j, const HsaoSettings& s);

// The farm's direction blocks (core/direction_blocks.hpp): hsao_texel sums each block of directions [d0, d1)
// from zero in double, adds the blocks in order as SplitDouble (48 bits) and finishes; `hfbake merge` adds
// blocks baked elsewhere the same way, so both give the same bits.
struct HsaoSums {
  SplitDouble horizon, normal;  // O_T and O_N of the block's directions
  SplitDouble bent[3];          // the block's unnormalised bent direction
};
HsaoSums hsao_texel_sums(const HeightField& field, Vec3 normal, int i, int j, const HsaoSettings& s, int d0,
                         int d1);
void hsao_add_sums(HsaoSums& total, const HsaoSums& block);
HsaoTexel hsao_finish(const HsaoSums& sums, Vec3 normal);

// Whole field, rows in parallel (deterministic). obscurance = 1 - (O_T + O_N); either output may be null.
void hsao_field(const HeightField& field, const std::vector<Vec3f>& normals, const HsaoSettings& s,
                const RunControl& rc, float* obscurance, float* bent_xyz);

// Reads and checks an hsao bake entry (schemas/methods/hsao.schema.json).
HsaoSettings read_hsao_settings(Params& in, const FieldShape& field);

}  // namespace hfbake
