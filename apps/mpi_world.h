// Rendering across processes with MPI (`mpirun -np N kozu render ...`, docs/production.md). Each rank renders every
// N-th tile of the image (tile i on rank i mod N: interleaved, so each rank gets a share of every region), with
// the same per-pixel sample streams as one process; the films are then summed onto rank 0, which writes the
// outputs. A pixel is rendered by exactly one rank and the others contribute zeros, so the sum is exact: the image is
// bit-identical to a single-process render with the same seed and spp.
//
// MPI starts only when kozu was launched by an MPI launcher (OMPI_COMM_WORLD_SIZE or PMI_SIZE in the
// environment), so a plain `kozu render` never pays for it. Built only with KOZU_HAVE_MPI (CMake: KOZU_MPI).
#pragma once

#include "integrators/integrator.h"
#include "render/film.h"

namespace kozu::app {

class MpiWorld {
 public:
  // Starts MPI when launched under mpirun (else a world of one).
  MpiWorld(int* argc, char*** argv);
  ~MpiWorld();  // finalizes MPI if it was started
  MpiWorld(const MpiWorld&) = delete;
  MpiWorld& operator=(const MpiWorld&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool distributed() const { return size_ > 1; }

  // Sums every rank's film (and features) and ray counters onto rank 0's; false (with a message) on MPI failure.
  bool reduce(Film& film, RayCounters& rays, uint64_t& paths) const;
  // The largest value of x over the ranks, on every rank.
  double max(double x) const;

  // Collective: every rank states whether it is ready (status 0) and what it is about to render (a fingerprint of
  // the settings that decide which pixels and samples each rank takes and the film's layout). On every rank: the
  // worst status and the lowest rank that has it, and the first rank whose fingerprint differs from rank 0's (-1:
  // none). A rank that fails calls it too (with its status), so no rank is left waiting in a later collective.
  struct Agreement {
    int status = 0, failed_rank = -1, mismatched_rank = -1;
    bool ok() const { return status == 0 && mismatched_rank < 0; }
  };
  Agreement agree(int status, uint64_t fingerprint) const;

  static MpiWorld* instance();  // the world main() made, or null

 private:
  bool started_ = false;
  int rank_ = 0, size_ = 1;
};

}  // namespace kozu::app
