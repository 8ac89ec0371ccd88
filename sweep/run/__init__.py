"""Running a campaign: the worker protocol, the master and its workers, and their transports.

Layers, each module importing only those above it: :mod:`.protocol` (the Task and
Outcome messages), :mod:`.signals` and :mod:`.guard` (stop signals), :mod:`.compute`
(one point computed), :mod:`.warmup`, :mod:`.transport` (in-process and MPI),
:mod:`.worker` (the MPI worker loop), :mod:`.progress`, :mod:`.plan`, :mod:`.master`
(scheduling and group commits) and :mod:`.launch` (:func:`~.launch.run_campaign`).
"""
