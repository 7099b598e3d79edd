/* The few MPI and IceT calls lacuna makes (feature `mpi`), behind a plain C
 * interface: compiled against the real mpi.h and IceT.h by build.rs, so
 * MPI_Comm and the IceT enums keep their implementation's ABI and values,
 * and the Rust side declares only ints, doubles and float pointers
 * (src/parallel/mpi.rs). */
#include <IceT.h>
#include <IceTMPI.h>
#include <mpi.h>
#include <stdlib.h>
#include <string.h>

int lacuna_mpi_init(int *rank, int *size) {
    int ready = 0;
    MPI_Initialized(&ready);
    if (!ready && MPI_Init(NULL, NULL) != MPI_SUCCESS) {
        return 0;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, size);
    return 1;
}

void lacuna_mpi_finalize(void) {
    int done = 0;
    MPI_Finalized(&done);
    if (!done) {
        MPI_Finalize();
    }
}

/* The smallest of every rank's v (every rank gets it). */
int lacuna_mpi_min(int v) {
    int out = v;
    MPI_Allreduce(&v, &out, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    return out;
}

/* One round of the ranks' streaming agreement (src/parallel/mpi.rs): the
 * least lo and greatest hi over every rank in out[0..2], whether any rank
 * failed (out[2]), whether any rank is done streaming (out[3]) and whether
 * every rank is (out[4]), each 1 or 0. Every rank gets the same answer. */
void lacuna_mpi_stream_round(double lo, double hi, int failed, int done, double *out) {
    /* Negated where the wanted reduction is a maximum, so one MPI_MIN
     * reduces them all. */
    double mine[5] = {lo, -hi, failed ? -1.0 : 0.0, done ? -1.0 : 0.0, done ? 0.0 : -1.0};
    double all[5] = {0, 0, 0, 0, 0};
    MPI_Allreduce(mine, all, 5, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
    out[0] = all[0];
    out[1] = -all[1];
    out[2] = all[2] < 0.0;
    out[3] = all[3] < 0.0;
    out[4] = all[4] == 0.0;
}

/* Per pixel, the RGBA (n pixels) of the rank whose value is the largest
 * (largest != 0) or the smallest, the lowest such rank on ties, on rank 0
 * in out (n * 4 floats; unused elsewhere), and the wall ms it took. One
 * MAXLOC (MINLOC) reduction finds each pixel's rank; a sum then carries
 * the winners' colours to rank 0, every other rank adding exact zeros.
 * Returns 0 on success. Every rank must call it. */
int lacuna_mpi_pick(int n, const float *value, int largest, const float *rgba, float *out, double *ms) {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    struct pair {
        float value;
        int rank;
    };
    struct pair *mine = malloc((size_t)n * sizeof *mine);
    struct pair *won = malloc((size_t)n * sizeof *won);
    float *colour = malloc((size_t)n * 4 * sizeof *colour);
    int ok = mine && won && colour;
    /* Every rank allocated, or none goes on (a collective must not wait). */
    int all_ok = 0;
    MPI_Allreduce(&ok, &all_ok, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    int status = 1;
    if (all_ok) {
        MPI_Barrier(MPI_COMM_WORLD);
        double start = MPI_Wtime();
        for (int i = 0; i < n; ++i) {
            mine[i].value = value[i];
            mine[i].rank = rank;
        }
        MPI_Allreduce(mine, won, n, MPI_FLOAT_INT, largest ? MPI_MAXLOC : MPI_MINLOC, MPI_COMM_WORLD);
        for (int i = 0; i < n; ++i) {
            for (int c = 0; c < 4; ++c) {
                colour[4 * i + c] = won[i].rank == rank ? rgba[4 * i + c] : 0.0f;
            }
        }
        MPI_Reduce(colour, out, 4 * n, MPI_FLOAT, MPI_SUM, 0, MPI_COMM_WORLD);
        *ms = (MPI_Wtime() - start) * 1e3;
        status = 0;
    }
    free(mine);
    free(won);
    free(colour);
    return status;
}

/* Ends every rank (a rank that panicked: the others would wait for it). */
void lacuna_mpi_abort(int code) {
    MPI_Abort(MPI_COMM_WORLD, code);
}

void lacuna_mpi_barrier(void) {
    MPI_Barrier(MPI_COMM_WORLD);
}

/* Every rank's n values, in rank order, on rank 0 (out: n * size values
 * there; unused elsewhere). */
void lacuna_mpi_gather(const double *values, int n, double *out) {
    MPI_Gather(values, n, MPI_DOUBLE, out, n, MPI_DOUBLE, 0, MPI_COMM_WORLD);
}

/* Composites every rank's premultiplied RGBA float image (width x height,
 * the same layout on every rank) by IceT's ordered blend: order lists the
 * ranks front to back. Rank 0 receives the result in out (width * height *
 * 4 floats) and ms the compositing's wall time. Returns IceT's error
 * (ICET_NO_ERROR is 0). Every rank must call it. */
int lacuna_icet_composite(int width, int height, const float *rgba, const int *order, float *out, double *ms) {
    IceTCommunicator comm = icetCreateMPICommunicator(MPI_COMM_WORLD);
    IceTContext context = icetCreateContext(comm);
    icetDiagnostics(ICET_DIAG_ERRORS | ICET_DIAG_ALL_NODES);
    icetSetColorFormat(ICET_IMAGE_COLOR_RGBA_FLOAT);
    icetSetDepthFormat(ICET_IMAGE_DEPTH_NONE);
    icetCompositeMode(ICET_COMPOSITE_MODE_BLEND);
    /* One tile: sequential is IceT's recommendation; it orders. */
    icetStrategy(ICET_STRATEGY_SEQUENTIAL);
    icetSingleImageStrategy(ICET_SINGLE_IMAGE_STRATEGY_AUTOMATIC);
    icetEnable(ICET_ORDERED_COMPOSITE);
    icetCompositeOrder(order);
    icetResetTiles();
    icetAddTile(0, 0, width, height, 0);
    icetPhysicalRenderSize(width, height);
    const IceTDouble identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const IceTFloat background[4] = {0, 0, 0, 0};
    MPI_Barrier(MPI_COMM_WORLD);
    double start = MPI_Wtime();
    IceTImage image = icetCompositeImage(rgba, NULL, NULL, identity, identity, background);
    double end = MPI_Wtime();
    IceTEnum error = icetGetError();
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (error == ICET_NO_ERROR && rank == 0) {
        memcpy(out, icetImageGetColorcf(image), (size_t)width * (size_t)height * 4 * sizeof(float));
    }
    *ms = (end - start) * 1e3;
    icetDestroyContext(context);
    icetDestroyMPICommunicator(comm);
    return (int)error;
}
