#include "calibration/ranks.h"

#include <cstdio>
#include <cstdlib>

#include "core/error.h"
#include "core/interrupt.h"

#ifdef DEMLAB_MPI
#include <mpi.h>
#endif

namespace demlab {

namespace {
const Ranks* g_started = nullptr;  // the world, once made
}

Ranks& Ranks::world() {
    static Ranks r;
    g_started = &r;
    return r;
}

Ranks::Ranks() {
#ifdef DEMLAB_MPI
    if (std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMI_SIZE")) {
        MPI_Init(nullptr, nullptr);
        MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
        MPI_Comm_size(MPI_COMM_WORLD, &size_);
        started_ = true;
    }
#else
    // several copies of a build without MPI would each run every job into the same folder
    const char* n = std::getenv("OMPI_COMM_WORLD_SIZE");
    if (!n) n = std::getenv("PMI_SIZE");
    if (n && std::atoi(n) > 1)
        throw InputError("demlab was built without MPI (libopenmpi-dev was missing when it was configured): run the "
                         "sweep with --jobs on one machine, or rebuild after scripts/install-deps.sh");
#endif
}

Ranks::~Ranks() {
#ifdef DEMLAB_MPI
    if (started_) MPI_Finalize();
#endif
}

int Ranks::max_over_ranks(int value) const {
#ifdef DEMLAB_MPI
    if (started_) {
        int largest = value;
        MPI_Allreduce(&value, &largest, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
        return largest;
    }
#endif
    return value;
}

void Ranks::abort_others(const char* message, int code) {
#ifdef DEMLAB_MPI
    if (g_started && g_started->started_ && g_started->size_ > 1) {
        std::fprintf(stderr, "demlab (rank %d of %d): %s\n", g_started->rank_, g_started->size_, message);
        std::fflush(stderr);
        MPI_Abort(MPI_COMM_WORLD, code);
    }
#else
    (void)message;
    (void)code;
#endif
}

int Ranks::run_command(const std::function<int()>& command) {
    try {
        return command();
    } catch (const InputError& e) {
        abort_others(e.what(), kExitInput);
        throw;
    } catch (const Interrupted& e) {
        abort_others(e.what(), kExitInterrupted);
        throw;
    } catch (const WriteError& e) {
        abort_others(e.what(), kExitWrite);
        throw;
    } catch (const std::exception& e) {
        abort_others(e.what(), kExitRun);
        throw;
    }
}

bool have_mpi() {
#ifdef DEMLAB_MPI
    return true;
#else
    return false;
#endif
}

}  // namespace demlab
