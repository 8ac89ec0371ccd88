"""The study of Herman, Cheng & Shen (2019) on floewave, above sweep (as PySDM keeps
``PySDM_examples/<Author_Year>/`` apart from PySDM): it imports floewave and sweep, and
neither imports it. The command is ``herman2019`` (:mod:`.cli`; ``python -m herman2019``).

The paper's qualitative claims checked on the stores of the shipped paper campaigns:
:mod:`.estimates` (estimates with standard errors and the rules comparing them),
:mod:`.claims` (the claims, one check each, with :mod:`.points`, :mod:`.zones`,
:mod:`.shapes`, :mod:`.exponents`, :mod:`.scan`, :mod:`.traces`, :mod:`.variants`),
:mod:`.check` (the campaigns run or read, and the table), :mod:`.seeds` (the same across
seeds), :mod:`.settle` with :mod:`.pooling`, :mod:`.sequential`, :mod:`.thresholds` and
:mod:`.settled` (every verdict settled over seeds), :mod:`.dfscan` (the d_f scan at
T = 1.8 s and its figure, docs/dfscan.md) and :mod:`.report` (the table in a campaign
report). The shipped documents and results: :mod:`.atlas` (docs/atlas.md),
:mod:`.numbers` (docs/numbers.txt) and :mod:`.record` (results/herman2019/).
"""
