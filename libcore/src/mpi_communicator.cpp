// The MPI implementation of Communicator, compiled when ctk is built with OpenMPI.
#include <mpi.h>

#include <algorithm>
#include <cstdlib>
#include <limits>

#include "ctk/core/communicator.hpp"

namespace ctk {

namespace {

// Whether an MPI launcher started this process (OpenMPI's mpirun, or any PMIx/PMI launcher):
// without one, MPI is not initialised and the run is a single process.
bool launched_by_mpi() {
  for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"})
    if (std::getenv(variable)) return true;
  return false;
}

// MPI counts are ints: long arrays (a 2048^3 volume has 2^33 voxels) go in pieces.
constexpr std::size_t kPiece = std::size_t{1} << 28;

class MpiWorld final : public Communicator {
 public:
  MpiWorld() {
    int provided = 0;
    // Only the thread that called MPI_Init calls MPI (OpenMP threads never do).
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    // An error in any MPI call ends the job (the default), so no rank waits for a dead one.
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_ARE_FATAL);
  }
  ~MpiWorld() override {
    int finalised = 0;
    MPI_Finalized(&finalised);
    if (!finalised) MPI_Finalize();
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  using Communicator::sum;
  void sum(std::span<float> values) const override { sum_pieces(values, MPI_FLOAT); }
  void sum(std::span<double> values) const override { sum_pieces(values, MPI_DOUBLE); }

  std::vector<std::string> gather(const std::string& text) const override {
    const int length = static_cast<int>(text.size());
    std::vector<int> lengths(static_cast<std::size_t>(size_)), offsets(static_cast<std::size_t>(size_));
    MPI_Allgather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, MPI_COMM_WORLD);
    int total = 0;
    for (int r = 0; r < size_; ++r) {
      offsets[static_cast<std::size_t>(r)] = total;
      total += lengths[static_cast<std::size_t>(r)];
    }
    std::string all(static_cast<std::size_t>(total), '\0');
    MPI_Allgatherv(text.data(), length, MPI_CHAR, all.data(), lengths.data(), offsets.data(), MPI_CHAR, MPI_COMM_WORLD);
    bytes_sent_ += text.size() + sizeof(int);
    std::vector<std::string> out;
    for (int r = 0; r < size_; ++r)
      out.push_back(all.substr(static_cast<std::size_t>(offsets[static_cast<std::size_t>(r)]),
                               static_cast<std::size_t>(lengths[static_cast<std::size_t>(r)])));
    return out;
  }

  [[noreturn]] void abort(int exit_code) const override {
    MPI_Abort(MPI_COMM_WORLD, exit_code);
    std::exit(exit_code);  // MPI_Abort does not return; this satisfies [[noreturn]]
  }

 private:
  // MPI_Allreduce's algorithm is a fixed schedule chosen from the rank count and the message
  // length, so the additions' order does not depend on timing.
  template <typename T>
  void sum_pieces(std::span<T> values, MPI_Datatype type) const {
    for (std::size_t begin = 0; begin < values.size(); begin += kPiece) {
      const std::size_t n = std::min(kPiece, values.size() - begin);
      MPI_Allreduce(MPI_IN_PLACE, values.data() + begin, static_cast<int>(n), type, MPI_SUM, MPI_COMM_WORLD);
    }
    bytes_sent_ += values.size_bytes();
  }
  int rank_ = 0, size_ = 1;
};

}  // namespace

const Communicator& world() {
  if (!launched_by_mpi()) return single_process();
  static const MpiWorld mpi;
  return mpi;
}

bool built_with_mpi() { return true; }

}  // namespace ctk
