// Writes the NanoVDB test fixtures of crates/io/tests/nanovdb.rs with the official NanoVDB
// library (32.4, the one in OpenVDB 10.0.1), so the Rust reader is tested against files it did
// not write itself.
//
// Build and run (Debian: apt-get install libnanovdb-dev zlib1g-dev):
//
//     g++ -O2 -std=c++17 scripts/nanovdb-fixture.cpp -o /tmp/gen -lz
//     /tmp/gen crates/io/tests/data/nanovdb
//
// Files written to the directory given:
//
// - ramp.nvdb.gz: one float FogVolume grid "density", uncompressed (Codec NONE), then gzipped
//   here for the repository (an uncompressed grid is at least ~300 KB: the 32³ upper node's
//   table alone is 256 KB of mostly zeros). Values: ramp() below on three boxes (one of them
//   constant over two whole 8³ leaves, which the builder prunes to tiles), background 0; the
//   index-to-world map is a rotation times a uniform voxel size 0.05 plus a translation.
// - ramp-zip.nvdb: a grid "other" and then the same "density" grid, ZIP-compressed.
// - ramp-samples.txt: lines "x y z value": 400 world points in and around the density grid's
//   world box and its active voxels, and the density there as pbrt-v4's NanoVDBMedium reads it
//   (NanoVDB's own world-to-index map and trilinear sampler; 0 outside the world box).
// - fire.nvdb: ZIP; a fog sphere "density" (nanovdb::createFogVolumeSphere) and a constant
//   "temperature" grid of 1500 over a box, for the emission errors.
// - background.nvdb: ZIP; a float grid "density" with background 0.5 and a few active voxels.
// - double.nvdb: ZIP; a double-precision grid "density" (an unsupported grid type).
// - levelset.nvdb: ZIP; a level-set sphere "density" (class SDF, not a fog volume).
// - rim.nvdb: ZIP; a float grid "density" under rampMap() whose active voxels fill the box
//   rimLo..rimHi, with rim() below: positive inside, 0 on the box's outer layer (set active, so
//   the grid's bounding box is the whole box). Its medium is then the same function as a
//   pbrt uniformgrid of the same voxels (nothing for pbrt's clipping to the world box to cut).

#define NANOVDB_USE_ZIP 1
#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridBuilder.h>
#include <nanovdb/util/IO.h>
#include <nanovdb/util/Primitives.h>
#include <nanovdb/util/SampleFromVoxels.h>
#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

using nanovdb::Coord;
using nanovdb::CoordBBox;

// The density of the ramp grid at index (i, j, k); exact in single precision (dyadic
// rationals), different slopes per axis so a swapped axis order is seen. Returns 0 outside the
// three boxes (left inactive).
static float ramp(const Coord& c) {
    const int i = c[0], j = c[1], k = c[2];
    if (i >= -10 && i <= 13 && j >= -3 && j <= 6 && k >= 0 && k <= 17)
        return float(3 * (i + 10) + 5 * (j + 3) + 7 * k + 1) / 256.0f;
    if (i >= 40 && i <= 47 && j >= -3 && j <= -1 && k >= 30 && k <= 33)
        return float(32 + (i - 40) + 2 * (j + 3) + 4 * (k - 30)) / 32.0f;
    if (i >= 40 && i <= 55 && j >= 8 && j <= 15 && k >= 0 && k <= 7) return 0.75f;
    return 0.0f;
}

// The ramp grid's map: world = s · R · index + t, R = Rz(30°) · Rx(20°), s = 0.05.
static nanovdb::Map rampMap() {
    const double pi = 3.14159265358979323846;
    const double a = 30.0 * pi / 180.0, b = 20.0 * pi / 180.0, s = 0.05;
    const double rz[3][3] = {{std::cos(a), -std::sin(a), 0}, {std::sin(a), std::cos(a), 0}, {0, 0, 1}};
    const double rx[3][3] = {{1, 0, 0}, {0, std::cos(b), -std::sin(b)}, {0, std::sin(b), std::cos(b)}};
    double r[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            r[i][j] = 0;
            for (int k = 0; k < 3; ++k) r[i][j] += rz[i][k] * rx[k][j];
        }
    // Map::set takes matrices in OpenVDB's row-vector convention (world = index · mat):
    // mat = s·Rᵀ, and its inverse R / s.
    double mat[3][3], inv[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            mat[i][j] = s * r[j][i];
            inv[i][j] = r[i][j] / s;
        }
    nanovdb::Map map;
    map.set(mat, inv, nanovdb::Vec3d(0.3, -0.2, 0.5), 1.0);
    return map;
}

static nanovdb::GridHandle<> rampGrid(const char* name) {
    nanovdb::GridBuilder<float> builder(0.0f, nanovdb::GridClass::FogVolume);
    const auto f = [](const Coord& c) { return ramp(c); };
    builder(f, CoordBBox(Coord(-10, -3, 0), Coord(13, 6, 17)));
    builder(f, CoordBBox(Coord(40, -3, 30), Coord(47, -1, 33)));
    builder(f, CoordBBox(Coord(40, 8, 0), Coord(55, 15, 7)));
    return builder.getHandle<>(rampMap(), name);
}

// The rim grid's voxel box and values: a ramp strictly inside, 0 on the outer layer.
static const Coord rimLo(-3, -2, 0), rimHi(12, 9, 13);
static float rim(const Coord& c) {
    for (int a = 0; a < 3; ++a)
        if (c[a] <= rimLo[a] || c[a] >= rimHi[a]) return 0.0f;
    return float(3 * (c[0] - rimLo[0]) + 5 * (c[1] - rimLo[1]) + 7 * (c[2] - rimLo[2])) / 64.0f;
}

static void gzipFile(const std::string& from, const std::string& to) {
    std::ifstream in(from, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string bytes = ss.str();
    gzFile out = gzopen(to.c_str(), "wb9");
    gzwrite(out, bytes.data(), unsigned(bytes.size()));
    gzclose(out);
}

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s OUTPUT_DIRECTORY\n", argv[0]);
        return 2;
    }
    const std::string dir = argv[1];
    using nanovdb::io::Codec;

    auto density = rampGrid("density");
    const std::string raw = dir + "/ramp.nvdb";
    nanovdb::io::writeGrid(raw, density, Codec::NONE);
    gzipFile(raw, raw + ".gz");
    std::remove(raw.c_str());

    {
        std::vector<nanovdb::GridHandle<>> handles;
        nanovdb::GridBuilder<float> other(0.0f, nanovdb::GridClass::FogVolume);
        other([](const Coord& c) { return float(c[0] + 2 * c[1] + 4 * c[2] + 8); },
              CoordBBox(Coord(0, 0, 0), Coord(3, 3, 3)));
        handles.push_back(other.getHandle<>(1.0, nanovdb::Vec3d(0.0), "other"));
        handles.push_back(rampGrid("density"));
        nanovdb::io::writeGrids(dir + "/ramp-zip.nvdb", handles, Codec::ZIP);
    }

    {
        // pbrt-v4's lookup: medium point → index space (single precision), trilinear.
        const nanovdb::FloatGrid* grid = density.grid<float>();
        using Sampler = nanovdb::SampleFromVoxels<nanovdb::FloatGrid::TreeType, 1, false>;
        Sampler sampler(grid->tree());
        const auto box = grid->worldBBox();
        std::mt19937 rng(7);
        std::FILE* out = std::fopen((dir + "/ramp-samples.txt").c_str(), "w");
        for (int n = 0; n < 400; ++n) {
            // A quarter anywhere around the world box, the rest near the active boxes.
            double p[3];
            if (n % 4 == 0) {
                for (int a = 0; a < 3; ++a) {
                    const double lo = box.min()[a], hi = box.max()[a], pad = 0.05 * (hi - lo);
                    p[a] = std::uniform_real_distribution<double>(lo - pad, hi + pad)(rng);
                }
            } else {
                const int boxes[3][6] = {{-10, -3, 0, 13, 6, 17}, {40, -3, 30, 47, -1, 33}, {40, 8, 0, 55, 15, 7}};
                const int* b = boxes[n % 3];
                nanovdb::Vec3d index;
                for (int a = 0; a < 3; ++a)
                    index[a] = std::uniform_real_distribution<double>(b[a] - 1.5, b[a + 3] + 1.5)(rng);
                const nanovdb::Vec3d world = grid->indexToWorld(index);
                for (int a = 0; a < 3; ++a) p[a] = world[a];
            }
            // The printed (rounded) point is the one sampled.
            char text[128];
            std::snprintf(text, sizeof text, "%.9g %.9g %.9g", p[0], p[1], p[2]);
            std::sscanf(text, "%lf %lf %lf", &p[0], &p[1], &p[2]);
            const float x = float(p[0]), y = float(p[1]), z = float(p[2]);
            bool inside = true;
            for (int a = 0; a < 3; ++a) inside = inside && float(p[a]) >= float(box.min()[a]) && float(p[a]) <= float(box.max()[a]);
            const auto index = grid->worldToIndexF(nanovdb::Vec3f(x, y, z));
            const float value = inside ? sampler(index) : 0.0f;
            std::fprintf(out, "%s %.9g\n", text, value);
        }
        std::fclose(out);
    }

    {
        std::vector<nanovdb::GridHandle<>> handles;
        handles.push_back(nanovdb::createFogVolumeSphere<float>(0.5f, nanovdb::Vec3f(0.0f), 0.1, 2.0,
                                                                nanovdb::Vec3d(0.0), "density"));
        nanovdb::GridBuilder<float> temperature(0.0f, nanovdb::GridClass::FogVolume);
        temperature([](const Coord&) { return 1500.0f; }, CoordBBox(Coord(-4, -4, -4), Coord(3, 3, 3)));
        handles.push_back(temperature.getHandle<>(0.1, nanovdb::Vec3d(0.0), "temperature"));
        nanovdb::io::writeGrids(dir + "/fire.nvdb", handles, Codec::ZIP);
    }

    {
        nanovdb::GridBuilder<float> builder(0.5f, nanovdb::GridClass::FogVolume);
        builder([](const Coord& c) { return c == Coord(1, 2, 3) ? 2.0f : c == Coord(9, 2, 3) ? 1.0f : 0.5f; },
                CoordBBox(Coord(0, 0, 0), Coord(10, 4, 4)));
        nanovdb::io::writeGrid(dir + "/background.nvdb", builder.getHandle<>(1.0, nanovdb::Vec3d(0.0), "density"),
                               Codec::ZIP);
    }

    {
        nanovdb::GridBuilder<double> builder(0.0, nanovdb::GridClass::FogVolume);
        builder([](const Coord&) { return 1.0; }, CoordBBox(Coord(0, 0, 0), Coord(2, 2, 2)));
        nanovdb::io::writeGrid(dir + "/double.nvdb", builder.getHandle<>(1.0, nanovdb::Vec3d(0.0), "density"),
                               Codec::ZIP);
    }

    {
        nanovdb::GridBuilder<float> builder(0.0f, nanovdb::GridClass::FogVolume);
        auto acc = builder.getAccessor();
        for (int i = rimLo[0]; i <= rimHi[0]; ++i)
            for (int j = rimLo[1]; j <= rimHi[1]; ++j)
                for (int k = rimLo[2]; k <= rimHi[2]; ++k) acc.setValue(Coord(i, j, k), rim(Coord(i, j, k)));
        nanovdb::io::writeGrid(dir + "/rim.nvdb", builder.getHandle<>(rampMap(), "density"), Codec::ZIP);
    }

    nanovdb::io::writeGrid(dir + "/levelset.nvdb",
                           nanovdb::createLevelSetSphere<float>(0.3f, nanovdb::Vec3f(0.0f), 0.1, 2.0,
                                                                nanovdb::Vec3d(0.0), "density"),
                           Codec::ZIP);
    return 0;
}
