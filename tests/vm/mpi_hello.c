/* mpi_hello: the smallest MPI program that exercises what a multi-rank test
 * needs from OpenMPI in the VM guest (tests/vm/mpi_smoke.sh).
 *
 * Every rank prints "mpi_hello: rank R of N on HOST (pid P)", waits at an
 * MPI_Barrier, then all ranks MPI_Allreduce the sum of their rank numbers;
 * each checks it is N*(N-1)/2 and prints "mpi_hello: rank R sum S ok" (or
 * "... sum S expected E" and exits 1). Rank 0 prints "mpi_hello: done N"
 * after a second barrier. Exit status 0 only if every check passed.
 *
 * build: mpicc -std=c11 -O2 -Wall -Wextra -o mpi_hello mpi_hello.c
 * run:   mpirun --oversubscribe --bind-to none -np 2 ./mpi_hello
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <unistd.h>

#include <mpi.h>

int main(int argc, char **argv)
{
    int rank = -1, size = 0, len = 0;
    char host[MPI_MAX_PROCESSOR_NAME] = "?";

    if (MPI_Init(&argc, &argv) != MPI_SUCCESS) {
        fprintf(stderr, "mpi_hello: MPI_Init failed\n");
        return 1;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    MPI_Get_processor_name(host, &len);
    printf("mpi_hello: rank %d of %d on %s (pid %ld)\n", rank, size, host, (long)getpid());
    fflush(stdout);

    int failed = MPI_Barrier(MPI_COMM_WORLD) != MPI_SUCCESS;

    long mine = rank, sum = -1, want = (long)size * (size - 1) / 2;
    if (MPI_Allreduce(&mine, &sum, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD) != MPI_SUCCESS) failed = 1;
    if (sum == want) {
        printf("mpi_hello: rank %d sum %ld ok\n", rank, sum);
    } else {
        printf("mpi_hello: rank %d sum %ld expected %ld\n", rank, sum, want);
        failed = 1;
    }
    fflush(stdout);

    /* everybody's lines are out before rank 0 says done */
    if (MPI_Barrier(MPI_COMM_WORLD) != MPI_SUCCESS) failed = 1;
    if (rank == 0 && !failed) printf("mpi_hello: done %d\n", size);
    fflush(stdout);
    MPI_Finalize();
    return failed;
}
