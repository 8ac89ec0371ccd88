"""Running a campaign: the master and its workers, their transports, stop signals and plans.

Each module imports only those before it in this list (and the layers below
:mod:`sweep.run`: :mod:`sweep.protocol`, :mod:`sweep.store`, ...): :mod:`.signals`,
:mod:`.guard` and :mod:`.mpi` (stop signals, the launch), :mod:`.startup` (stops during a
command's start-up), :mod:`.compute` (one point
computed into an Outcome), :mod:`.warmup`, :mod:`.transport` (in-process and MPI),
:mod:`.worker` (the MPI worker loop), :mod:`.progress`, :mod:`.plan`, :mod:`.master`
(scheduling and group commits) and :mod:`.launch` (:func:`~.launch.run_campaign`).
"""
