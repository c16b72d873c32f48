// Deterministic test and demo inputs: evenly sampled shapes and lattices.
//
// Everything here is generated from a seed with a fully specified generator (mt19937_64),
// so the same call gives the same points on every machine.
#pragma once

#include <cstddef>
#include <cstdint>

#include "particlemesh/core/export.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace particlemesh {

/// n points on a sphere by the Fibonacci (golden-angle) spiral, with outward normals.
/// Spacing is about radius * sqrt(4 pi / n) * 0.95.
PM_EXPORT PointCloud fibonacci_sphere(size_t n, double radius = 1.0, Vec3 center = {});

/// A closed torus mesh (major radius R, minor radius r) with nu x nv quads split in two.
PM_EXPORT TriMesh torus_mesh(double R, double r, int nu, int nv);

/// A closed tube of radius `tube_radius` around the trefoil knot
/// (sin t + 2 sin 2t, cos t - 2 cos 2t, -sin 3t) scaled by `scale`, nu segments along the
/// knot and nv around the tube, outward winding.
PM_EXPORT TriMesh trefoil_tube_mesh(double scale, double tube_radius, int nu, int nv);

/// An icosphere: the icosahedron subdivided `levels` times, vertices on the sphere.
PM_EXPORT TriMesh icosphere_mesh(int levels, double radius = 1.0);

/// Maximal Poisson-disk sample of a triangle mesh: area-uniform random candidates
/// (`oversampling` per r0^2 of area), visited in random order, each kept iff no kept point is
/// within r0. Every pair of points is at least r0 apart and the surface is covered to about
/// r0. Normals are the sampled triangles' unit normals (their winding).
PM_EXPORT PointCloud poisson_disk_sample(const TriMesh& mesh, double r0, uint64_t seed = 1,
                                         double oversampling = 30.0);

/// nx x ny points of a flat square lattice (z = 0) with the given spacing.
PM_EXPORT PointCloud square_lattice(int nx, int ny, double spacing = 1.0);

/// nx x ny points of a flat hexagonal (triangular) lattice (z = 0) with the given spacing.
PM_EXPORT PointCloud hex_lattice(int nx, int ny, double spacing = 1.0);

}  // namespace particlemesh
