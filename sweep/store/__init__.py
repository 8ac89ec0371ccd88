"""The campaign store: one HDF5 file of points beside a checksummed journal, its schema and repair.

Each module imports only those before it in this list: :mod:`.schema` (the on-disk
layout), :mod:`.migrate` (older layouts brought up to date), :mod:`.document` (the schema
as JSON), :mod:`.cells` (values to and from stored cells), :mod:`.lock`, :mod:`.journal`
(the durable truth), :mod:`.record` (one stored point), :mod:`.reader`, :mod:`.writer`
(HDF5 I/O), :mod:`.validate`, :mod:`.verify` and :mod:`.campaign_check` (checks),
:mod:`.files` (the file's state, free space, inode lock), :mod:`.repair` (rebuilding
from the journal), :mod:`.store` (the :class:`~.store.Store` a campaign writes through)
and :mod:`.merge` (shard stores combined).
"""
