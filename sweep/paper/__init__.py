"""The paper's qualitative claims checked on the stores of the shipped paper campaigns.

:mod:`.estimates` (estimates with standard errors and the rules comparing them),
:mod:`.claims` (the claims, one check each), :mod:`.check` (the campaigns run or read,
and the table) and :mod:`.seeds` (the same across seeds).
"""
