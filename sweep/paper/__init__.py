"""The paper's qualitative claims checked on the stores of the shipped paper campaigns.

:mod:`.estimates` (estimates with standard errors and the rules comparing them),
:mod:`.claims` (the claims, one check each), :mod:`.check` (the campaigns run or read,
and the table), :mod:`.seeds` (the same across seeds) and :mod:`.dfscan` (the d_f scan
at T = 1.8 s and its figure, docs/dfscan.md).
"""
