#pragma once
// The ranks a run is spread over and the few collective operations distributed runs need: sums
// of arrays, every rank's text gathered, a failure that ends every rank. A process started
// without mpirun (or a build without MPI) has one rank, and every operation is then a no-op:
// nothing changes and MPI is never initialised.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace ctk {

class Communicator {
 public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;

  /// Every rank's `values` summed elementwise, the result on every rank (in place). The order of
  /// the additions depends only on the rank count and the array's length, never on timing, so a
  /// run repeated gives the same bits.
  virtual void sum(std::span<float> values) const = 0;
  virtual void sum(std::span<double> values) const = 0;
  double sum(double value) const;

  /// Every rank's `text`, in rank order, on every rank.
  virtual std::vector<std::string> gather(const std::string& text) const = 0;

  /// Rank q receives `to[q]` from every rank: returns what each rank sent this one, in rank order
  /// (`to` has size() entries; this rank's own entry comes back as it is).
  virtual std::vector<std::vector<float>> exchange(std::vector<std::vector<float>> to) const = 0;

  /// `values` to rank `to`, which takes them with receive(this rank, ...) into as many values.
  virtual void send(int to, std::span<const float> values) const = 0;
  virtual void receive(int from, std::span<float> values) const = 0;

  /// Ends every rank of the run with `exit_code` (after this rank has said why); one rank alone
  /// calls it.
  [[noreturn]] virtual void abort(int exit_code) const = 0;

  /// Bytes this rank has handed to collective operations so far (what the traffic model counts).
  std::size_t bytes_sent() const { return bytes_sent_; }

 protected:
  mutable std::size_t bytes_sent_ = 0;
};

/// The run of one process.
const Communicator& single_process();

/// This run's ranks: MPI's world when the process was started by mpirun (or another MPI launcher)
/// and ctk was built with MPI, otherwise single_process(). MPI is initialised on the first call
/// and finalised at exit.
const Communicator& world();

/// Whether this build can spread runs over MPI ranks.
bool built_with_mpi();

}  // namespace ctk
