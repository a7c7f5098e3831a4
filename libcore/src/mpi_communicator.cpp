// The MPI implementation of Communicator, compiled when ctk is built with OpenMPI.
#include <mpi.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <stdexcept>

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

// An exchange's counts and offsets are ints in MPI: beyond them the exchange is refused by name.
int checked_count(std::size_t n) {
  if (n > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::runtime_error("an exchange between MPI ranks of more than 2^31 values (use more ranks)");
  return static_cast<int>(n);
}

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
    out.reserve(static_cast<std::size_t>(size_));
    for (int r = 0; r < size_; ++r)
      out.push_back(all.substr(static_cast<std::size_t>(offsets[static_cast<std::size_t>(r)]),
                               static_cast<std::size_t>(lengths[static_cast<std::size_t>(r)])));
    return out;
  }

  std::vector<std::vector<float>> exchange(std::vector<std::vector<float>> to) const override {
    const auto n = static_cast<std::size_t>(size_);
    std::vector<int> send_counts(n), receive_counts(n), send_offsets(n), receive_offsets(n);
    std::size_t send_total = 0;
    for (std::size_t q = 0; q < n; ++q) {
      send_counts[q] = checked_count(to[q].size());
      send_offsets[q] = checked_count(send_total);
      send_total += to[q].size();
      if (static_cast<int>(q) != rank_) bytes_sent_ += to[q].size() * sizeof(float);
    }
    MPI_Alltoall(send_counts.data(), 1, MPI_INT, receive_counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    std::size_t receive_total = 0;
    for (std::size_t q = 0; q < n; ++q) {
      receive_offsets[q] = checked_count(receive_total);
      receive_total += static_cast<std::size_t>(receive_counts[q]);
    }
    std::vector<float> send(send_total), receive(receive_total);
    for (std::size_t q = 0; q < n; ++q) std::copy(to[q].begin(), to[q].end(), send.begin() + send_offsets[q]);
    MPI_Alltoallv(send.data(), send_counts.data(), send_offsets.data(), MPI_FLOAT, receive.data(), receive_counts.data(),
                  receive_offsets.data(), MPI_FLOAT, MPI_COMM_WORLD);
    std::vector<std::vector<float>> from(n);
    for (std::size_t q = 0; q < n; ++q)
      from[q].assign(receive.begin() + receive_offsets[q], receive.begin() + receive_offsets[q] + receive_counts[q]);
    return from;
  }

  // Point to point in pieces: a slab may have more values than an MPI count holds.
  void send(int to, std::span<const float> values) const override {
    for (std::size_t begin = 0; begin < values.size(); begin += kPiece)
      MPI_Send(values.data() + begin, static_cast<int>(std::min(kPiece, values.size() - begin)), MPI_FLOAT, to, 0,
               MPI_COMM_WORLD);
    bytes_sent_ += values.size_bytes();
  }
  void receive(int from, std::span<float> values) const override {
    for (std::size_t begin = 0; begin < values.size(); begin += kPiece)
      MPI_Recv(values.data() + begin, static_cast<int>(std::min(kPiece, values.size() - begin)), MPI_FLOAT, from, 0,
               MPI_COMM_WORLD, MPI_STATUS_IGNORE);
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
