"""What a worker waiting for its next task costs: the CPU share of ranks 1..N-1 that wait
in sweep's own loop (:func:`sweep.run.transport.wait_message`, sleeping backoff between
``Iprobe`` calls) while rank 0 sends nothing for ``SECONDS``.

    mpiexec -n 4 python benchmarks/worker_idle_cost.py [SECONDS]
    mpiexec -n 32 python benchmarks/worker_idle_cost.py 10

Prints the mean CPU share of a waiting worker. On a cluster each waits on a core of its
own; oversubscribed on a few cores, N waiting workers take N times that from the master
(docs/cluster.md, why ``bench_master.py --scale`` runs them under ``--nice-workers``).
"""
import sys
import time

from mpi4py import MPI

from sweep.run.transport import wait_message

comm = MPI.COMM_WORLD
seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 5.0
TAG = 5
if comm.Get_rank() == 0:
    time.sleep(seconds)
    for w in range(1, comm.Get_size()):
        comm.send(None, dest=w, tag=TAG)
    cpus = comm.gather(0.0, root=0)[1:]
    print(f"{comm.Get_size()} ranks: a waiting worker uses"
          f" {100 * sum(cpus) / len(cpus) / seconds:.2f} % of a core (mean of"
          f" {len(cpus)}, over {seconds:g} s)")
else:
    c0 = time.process_time()
    wait_message(comm, 0, TAG)
    comm.recv(source=0, tag=TAG)
    comm.gather(time.process_time() - c0, root=0)
