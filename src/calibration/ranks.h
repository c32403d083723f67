// The processes of a sweep: one without MPI, or the ranks of `mpirun -n N demlab calibrate`
// (Open MPI). The sweep spreads its runs over the ranks by index and shares nothing but the
// run folders (a file system all hosts see) and two collective calls: a barrier once the
// runs are done, and whether any rank failed. Every rank then reads every run's results from
// its folder and reaches the same figures; rank 0 writes the table.
#pragma once
#include <functional>

namespace demlab {

class Ranks {
public:
    // MPI is started only under a launcher (mpirun sets OMPI_COMM_WORLD_SIZE or PMI_SIZE):
    // a plain `demlab calibrate` runs as one rank without touching MPI.
    static Ranks& world();
    int rank() const { return rank_; }
    int size() const { return size_; }
    bool root() const { return rank_ == 0; }
    // waits for every rank; true if any rank passed failed = true
    bool any_failed(bool failed) const { return max_over_ranks(failed ? 1 : 0) != 0; }
    // waits for every rank; the largest value any rank passed
    int max_over_ranks(int value) const;
    // an error on this rank alone (after the last collective call): the others would wait
    // for it forever, so the message goes to stderr and mpirun stops them all (exit code)
    // (nothing when MPI was not started: an error every rank meets alike ends each alone)
    static void abort_others(const char* message, int code);
    // runs a sweep command; an exception from it first stops the other ranks (abort_others,
    // with the exit code `demlab` gives for it alone: 2 input, 4 interrupted, 5 a failed
    // write, 3 otherwise), then goes on to the caller
    static int run_command(const std::function<int()>& command);
    ~Ranks();

private:
    Ranks();
    int rank_ = 0, size_ = 1;
    bool started_ = false;
};

// Whether this build has MPI (CMake found it).
bool have_mpi();

}  // namespace demlab
