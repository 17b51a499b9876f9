#include "apps/mpi_world.h"

#include <mpi.h>

#include <cstdio>
#include <cstdlib>
#include <vector>

namespace kozu::app {

namespace {
MpiWorld* g_world = nullptr;
}

MpiWorld::MpiWorld(int* argc, char*** argv) {
  g_world = this;
  if (!std::getenv("OMPI_COMM_WORLD_SIZE") && !std::getenv("PMI_SIZE")) return;
  int provided = 0;
  // Only the main thread calls MPI (the render's TBB workers never do).
  if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
    std::fprintf(stderr, "error: kozu: MPI_Init failed; rendering as one process\n");
    return;
  }
  started_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiWorld::~MpiWorld() {
  if (started_) MPI_Finalize();
  g_world = nullptr;
}

MpiWorld* MpiWorld::instance() { return g_world; }

double MpiWorld::max(double x) const {
  if (!distributed()) return x;
  double out = x;
  MPI_Allreduce(&x, &out, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return out;
}

MpiWorld::Agreement MpiWorld::agree(int status, uint64_t fingerprint) const {
  Agreement a;
  if (!distributed()) {
    a.status = status;
    return a;
  }
  // The worst status, and the lowest rank that has it (MAXLOC breaks ties by the lower index).
  int in[2] = {status, rank_}, out[2] = {status, rank_};
  MPI_Allreduce(in, out, 1, MPI_2INT, MPI_MAXLOC, MPI_COMM_WORLD);
  a.status = out[0];
  a.failed_rank = out[0] != 0 ? out[1] : -1;
  std::vector<uint64_t> all(static_cast<size_t>(size_));
  MPI_Allgather(&fingerprint, 1, MPI_UINT64_T, all.data(), 1, MPI_UINT64_T, MPI_COMM_WORLD);
  if (a.status == 0)
    for (int r = 1; r < size_; ++r)
      if (all[static_cast<size_t>(r)] != all[0]) {
        a.mismatched_rank = r;
        break;
      }
  return a;
}

bool MpiWorld::reduce(Film& film, RayCounters& rays, uint64_t& paths) const {
  if (!distributed()) return true;
  const size_t n = film.pixels().size();
  // The accumulators as plain arrays: doubles and counts summed separately (exact: one rank holds each pixel).
  std::vector<double> sums(6 * n), sums_out(rank_ == 0 ? 6 * n : 0);
  std::vector<uint32_t> counts(2 * n), counts_out(rank_ == 0 ? 2 * n : 0);
  for (size_t i = 0; i < n; ++i) {
    const Film::Pixel& p = film.pixels()[i];
    for (int c = 0; c < 3; ++c) {
      sums[6 * i + c] = p.sum[c];
      sums[6 * i + 3 + c] = p.sum_sq[c];
    }
    counts[2 * i] = p.count;
    counts[2 * i + 1] = p.discarded;
  }
  // MPI counts are ints: send in chunks.
  constexpr size_t kChunk = size_t{1} << 26;
  auto reduce_chunks = [&](const void* in, void* out, size_t count, MPI_Datatype type, size_t elem) {
    for (size_t off = 0; off < count; off += kChunk) {
      const int m = static_cast<int>(std::min(kChunk, count - off));
      const char* src = static_cast<const char*>(in) + off * elem;
      char* dst = rank_ == 0 ? static_cast<char*>(out) + off * elem : nullptr;
      if (MPI_Reduce(src, dst, m, type, MPI_SUM, 0, MPI_COMM_WORLD) != MPI_SUCCESS) return false;
    }
    return true;
  };
  bool ok = reduce_chunks(sums.data(), sums_out.data(), sums.size(), MPI_DOUBLE, sizeof(double)) &&
            reduce_chunks(counts.data(), counts_out.data(), counts.size(), MPI_UINT32_T, sizeof(uint32_t));
  if (film.has_features()) {
    // The features and their visible emission's sums (sparse in the film, dense here) as floats, and the even count.
    static_assert(sizeof(Film::FeaturePixel) == 11 * 4, "features: 10 floats and a count");
    constexpr size_t kFloats = 17;
    std::vector<float> f(kFloats * n), f_out(rank_ == 0 ? kFloats * n : 0);
    std::vector<uint32_t> fc(n), fc_out(rank_ == 0 ? n : 0);
    for (size_t i = 0; i < n; ++i) {
      const Film::FeaturePixel& p = film.feature_pixels()[i];
      const EmissionSums::Pixel e = film.emission_sums().get(i);
      const float v[kFloats] = {p.albedo.x, p.albedo.y,   p.albedo.z,   p.normal.x,   p.normal.y, p.normal.z,
                                p.depth,    p.even_sum.x, p.even_sum.y, p.even_sum.z, e.sum.x,    e.sum.y,
                                e.sum.z,    e.even.x,     e.even.y,     e.even.z,     e.sq};
      std::copy(v, v + kFloats, &f[kFloats * i]);
      fc[i] = p.even_count;
    }
    ok = ok && reduce_chunks(f.data(), f_out.data(), f.size(), MPI_FLOAT, sizeof(float)) &&
         reduce_chunks(fc.data(), fc_out.data(), fc.size(), MPI_UINT32_T, sizeof(uint32_t));
    if (ok && rank_ == 0)
      for (size_t i = 0; i < n; ++i) {
        Film::FeaturePixel& p = film.feature_pixels()[i];
        const float* v = &f_out[kFloats * i];
        p.albedo = {v[0], v[1], v[2]};
        p.normal = {v[3], v[4], v[5]};
        p.depth = v[6];
        p.even_sum = {v[7], v[8], v[9]};
        p.even_count = fc_out[i];
        film.emission_sums().set(i, {{v[10], v[11], v[12]}, {v[13], v[14], v[15]}, v[16]});
      }
  }
  if (film.has_positions()) {
    // Position sums (--aov position): one rank holds each pixel, so the sum is that rank's.
    std::vector<float> out(rank_ == 0 ? 3 * n : 0);
    ok = ok && reduce_chunks(film.position_sums().data(), out.data(), 3 * n, MPI_FLOAT, sizeof(float));
    if (ok && rank_ == 0)
      for (size_t i = 0; i < n; ++i) film.position_sums()[i] = {out[3 * i], out[3 * i + 1], out[3 * i + 2]};
  }
  if (film.has_alpha()) {
    // Coverage counts (--alpha): integers, summed exactly.
    PixelBuffer<uint32_t> hits_out(rank_ == 0 ? n : 0);
    ok = ok && reduce_chunks(film.hit_counts().data(), hits_out.data(), n, MPI_UINT32_T, sizeof(uint32_t));
    if (ok && rank_ == 0) film.hit_counts() = std::move(hits_out);
  }
  uint64_t c[7] = {rays.camera_rays,     rays.extension_rays, rays.shadow_rays,         rays.probe_rays,
                   rays.truncated_paths, paths,               rays.tentative_collisions};
  uint64_t c_out[7] = {};
  ok = ok && MPI_Reduce(c, c_out, 7, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD) == MPI_SUCCESS;
  if (!ok) {
    std::fprintf(stderr, "error: kozu: MPI reduction of the film failed on rank %d\n", rank_);
    return false;
  }
  if (rank_ == 0) {
    for (size_t i = 0; i < n; ++i) {
      Film::Pixel& p = film.pixels()[i];
      for (int c2 = 0; c2 < 3; ++c2) {
        p.sum[c2] = sums_out[6 * i + c2];
        p.sum_sq[c2] = sums_out[6 * i + 3 + c2];
      }
      p.count = counts_out[2 * i];
      p.discarded = counts_out[2 * i + 1];
    }
    rays.camera_rays = c_out[0];
    rays.extension_rays = c_out[1];
    rays.shadow_rays = c_out[2];
    rays.probe_rays = c_out[3];
    rays.truncated_paths = c_out[4];
    paths = c_out[5];
    rays.tentative_collisions = c_out[6];
  }
  return true;
}

}  // namespace kozu::app
