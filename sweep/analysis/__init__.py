"""Reading and analysing a campaign's store: tables, profiles, statistics and figures.

:mod:`.load` (the store as pandas/xarray), :mod:`.stats` (collision-zone statistics and
alpha(omega) power laws), :mod:`.figures` (the paper's figures as PNG).
"""
