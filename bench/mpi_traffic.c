/* mpi_traffic — counts the bytes each rank hands to MPI to send (LD_PRELOAD, through the MPI
 * profiling interface) and prints them at MPI_Finalize:
 *   mpi_traffic: rank R of K sent B bytes in C calls
 * Point-to-point sends count their message; collectives count what this rank contributes (the
 * root's buffer of a broadcast, every rank's buffer of a reduce or gather). MPI's own
 * collectives run below this interface, so nothing is counted twice. Used by
 * bench/distributed_hig.sh to measure what a step exchanges, ScaLAPACK's traffic included. */
#include <mpi.h>
#include <stdio.h>

static unsigned long long sent_bytes = 0, sent_calls = 0;

static void count(int n, MPI_Datatype type) {
  int size = 0;
  PMPI_Type_size(type, &size);
  sent_bytes += (unsigned long long)n * (unsigned long long)size;
  ++sent_calls;
}

int MPI_Send(const void* b, int n, MPI_Datatype t, int d, int g, MPI_Comm c) {
  count(n, t);
  return PMPI_Send(b, n, t, d, g, c);
}
int MPI_Ssend(const void* b, int n, MPI_Datatype t, int d, int g, MPI_Comm c) {
  count(n, t);
  return PMPI_Ssend(b, n, t, d, g, c);
}
int MPI_Rsend(const void* b, int n, MPI_Datatype t, int d, int g, MPI_Comm c) {
  count(n, t);
  return PMPI_Rsend(b, n, t, d, g, c);
}
int MPI_Bsend(const void* b, int n, MPI_Datatype t, int d, int g, MPI_Comm c) {
  count(n, t);
  return PMPI_Bsend(b, n, t, d, g, c);
}
int MPI_Isend(const void* b, int n, MPI_Datatype t, int d, int g, MPI_Comm c, MPI_Request* r) {
  count(n, t);
  return PMPI_Isend(b, n, t, d, g, c, r);
}
int MPI_Issend(const void* b, int n, MPI_Datatype t, int d, int g, MPI_Comm c, MPI_Request* r) {
  count(n, t);
  return PMPI_Issend(b, n, t, d, g, c, r);
}
int MPI_Irsend(const void* b, int n, MPI_Datatype t, int d, int g, MPI_Comm c, MPI_Request* r) {
  count(n, t);
  return PMPI_Irsend(b, n, t, d, g, c, r);
}
int MPI_Sendrecv(const void* sb, int sn, MPI_Datatype st, int d, int sg, void* rb, int rn,
                 MPI_Datatype rt, int s, int rg, MPI_Comm c, MPI_Status* status) {
  count(sn, st);
  return PMPI_Sendrecv(sb, sn, st, d, sg, rb, rn, rt, s, rg, c, status);
}
int MPI_Bcast(void* b, int n, MPI_Datatype t, int root, MPI_Comm c) {
  int rank = 0;
  PMPI_Comm_rank(c, &rank);
  if (rank == root) count(n, t);
  return PMPI_Bcast(b, n, t, root, c);
}
int MPI_Reduce(const void* s, void* r, int n, MPI_Datatype t, MPI_Op op, int root, MPI_Comm c) {
  count(n, t);
  return PMPI_Reduce(s, r, n, t, op, root, c);
}
int MPI_Allreduce(const void* s, void* r, int n, MPI_Datatype t, MPI_Op op, MPI_Comm c) {
  count(n, t);
  return PMPI_Allreduce(s, r, n, t, op, c);
}
int MPI_Gather(const void* s, int sn, MPI_Datatype st, void* r, int rn, MPI_Datatype rt,
               int root, MPI_Comm c) {
  count(sn, st);
  return PMPI_Gather(s, sn, st, r, rn, rt, root, c);
}
int MPI_Gatherv(const void* s, int sn, MPI_Datatype st, void* r, const int* rn, const int* at,
                MPI_Datatype rt, int root, MPI_Comm c) {
  count(sn, st);
  return PMPI_Gatherv(s, sn, st, r, rn, at, rt, root, c);
}
int MPI_Allgather(const void* s, int sn, MPI_Datatype st, void* r, int rn, MPI_Datatype rt,
                  MPI_Comm c) {
  count(sn, st);
  return PMPI_Allgather(s, sn, st, r, rn, rt, c);
}
int MPI_Allgatherv(const void* s, int sn, MPI_Datatype st, void* r, const int* rn,
                   const int* at, MPI_Datatype rt, MPI_Comm c) {
  count(sn, st);
  return PMPI_Allgatherv(s, sn, st, r, rn, at, rt, c);
}
int MPI_Finalize(void) {
  int rank = 0, size = 1;
  PMPI_Comm_rank(MPI_COMM_WORLD, &rank);
  PMPI_Comm_size(MPI_COMM_WORLD, &size);
  fprintf(stderr, "mpi_traffic: rank %d of %d sent %llu bytes in %llu calls\n", rank, size,
          sent_bytes, sent_calls);
  return PMPI_Finalize();
}
