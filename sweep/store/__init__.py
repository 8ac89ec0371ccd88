"""The campaign store: one HDF5 file of points beside a checksummed journal, its schema and repair.

Layers, each module importing only those above it in this list: :mod:`.schema` (the
on-disk layout), :mod:`.migrate` (older layouts brought up to date), :mod:`.cells`
(values to and from stored cells), :mod:`.lock`, :mod:`.journal` (the durable truth),
:mod:`.record` (one stored point), :mod:`.reader`, :mod:`.writer` (HDF5 I/O),
:mod:`.validate`, :mod:`.verify` and :mod:`.campaign_check` (checks), :mod:`.repair`
(rebuilding a store from its journal), :mod:`.store` (the :class:`~.store.Store` a
campaign writes through) and :mod:`.merge` (shard stores combined).
"""
