// Deterministic test and demo inputs: evenly sampled shapes and lattices.
//
// Everything here is generated from a seed with a fully specified generator (mt19937_64),
// so the same call gives the same points on every machine.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <functional>

#include "particlemesh/core/export.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE {

/// n points on a sphere by the Fibonacci (golden-angle) spiral, with outward normals.
/// Spacing is about radius * sqrt(4 pi / n) * 0.95.
PM_EXPORT PointCloud fibonacci_sphere(size_t n, double radius = 1.0, Vec3 center = {});

/// A closed torus mesh (major radius R, minor radius r) with nu x nv quads split in two.
PM_EXPORT TriMesh torus_mesh(double R, double r, int nu, int nv);

/// A closed tube of radius `tube_radius` around the trefoil knot
/// (sin t + 2 sin 2t, cos t - 2 cos 2t, -sin 3t) scaled by `scale`, nu segments along the
/// knot and nv around the tube, outward winding.
PM_EXPORT TriMesh trefoil_tube_mesh(double scale, double tube_radius, int nu, int nv);

/// Shapes with sharp creases and corners (the edges of machined parts), for sampling:
/// a closed axis-aligned box from the origin to `size` (90-degree creases);
PM_EXPORT TriMesh box_mesh(Vec3 size);
/// a closed cone, base radius r on z = 0, apex at height h, nu sectors (its rim is a crease
/// of atan2(h, r) inside: 63 degrees at h = 2r);
PM_EXPORT TriMesh cone_mesh(double r, double h, int nu);
/// a closed triangular prism along z of the given height whose cross-section has two unit
/// legs meeting at `apex_deg` (creases of apex_deg and (180 - apex_deg) / 2 along it, 90 at
/// its ends).
PM_EXPORT TriMesh prism_mesh(double apex_deg, double height = 1.0);

/// An icosphere: the icosahedron subdivided `levels` times, vertices on the sphere.
PM_EXPORT TriMesh icosphere_mesh(int levels, double radius = 1.0);

/// Maximal Poisson-disk sample of a triangle mesh: area-uniform random candidates
/// (`oversampling` per r0^2 of area), visited in random order, each kept iff no kept point is
/// within r0. Every pair of points is at least r0 apart and the surface is covered to about
/// r0. Normals are the sampled triangles' unit normals (their winding).
PM_EXPORT PointCloud poisson_disk_sample(const TriMesh& mesh, double r0, uint64_t seed = 1,
                                         double oversampling = 30.0);

/// Maximal Poisson-disk sample of the implicit surface f = 0 inside the box [lo, hi]:
/// random points in the box are pulled onto the surface by Newton steps along grad f, then
/// kept in random order iff no kept point is within r0. Normals are grad f normalised (f < 0
/// inside, so they face outward). The darts are pulled in parallel (the caller's TBB arena),
/// so f and grad are called from several threads at once: they must be pure functions of the
/// point, as a surface's are. The sample is the same for any thread count.
PM_EXPORT PointCloud sample_implicit_surface(const std::function<double(const Vec3&)>& f,
                                             const std::function<Vec3(const Vec3&)>& grad, Vec3 lo, Vec3 hi,
                                             double r0, uint64_t seed = 1, size_t candidates = 0);

/// A closed genus-2 surface: the double torus (x (x-1)^2 (x-2) + y^2)^2 + z^2 = 0.04 (the
/// first coordinate spans about [-0.2, 2.2]), evenly sampled at spacing r0.
PM_EXPORT PointCloud double_torus_sample(double r0, uint64_t seed = 1);

/// nx x ny points of a flat square lattice (z = 0) with the given spacing.
PM_EXPORT PointCloud square_lattice(int nx, int ny, double spacing = 1.0);

/// nx x ny points of a flat hexagonal (triangular) lattice (z = 0) with the given spacing.
PM_EXPORT PointCloud hex_lattice(int nx, int ny, double spacing = 1.0);

}  // namespace particlemesh
