"""What each row of the table reads in the paper: the sentence (quoted verbatim from the
published text, The Cryosphere 13, 2887, with its section and figure), how it is read, and
the smallest effect the paper's figure or text could show (its **resolution**).

A row that fails is read against its resolution (:mod:`herman2019.outcomes`): an effect the
wrong way larger than the resolution contradicts the paper; one smaller than it is below
what the paper could show. The text gives the figures' captions, not their axes, so each
resolution is chosen from what the figure must hold (the curves this model draws at its
points) on a journal panel of 5-7 cm, and says so; those that are guesses say that too.

:data:`REWRITTEN`: the claims of the v8 settling (``results/paper-settle/settled.json``)
that are read otherwise since, and how.
"""
from __future__ import annotations

from dataclasses import dataclass

from herman2019.claims import NO_REVERSAL
from herman2019.points import A_RESOLUTION
from herman2019.variants import spring_claim
from herman2019.zones import BALANCE

__all__ = ["Resolution", "Reading", "READINGS", "REWRITTEN", "reading_of", "A_REL", "W_C",
           "X_OVER_W_C", "RATE_RATIO", "ALPHA", "DECADE", "EXPONENT", "SPIKES", "S_SD_RATIO",
           "DRIFT"]


@dataclass(frozen=True)
class Resolution:
    """The smallest effect [``unit``] the paper's figure or text could show, and why."""

    value: float
    unit: str
    why: str

    def text(self) -> str:
        return f"{self.value:g}{' ' + self.unit if self.unit else ''}"


A_REL = Resolution(A_RESOLUTION, "a0", "Figs. 2, 5, 6: a/a0 against x. Each panel holds curves"
                   " from 1 down to 0.42-0.75, so its axis spans at least half of a0: >= 0.007"
                   " a0 per mm on a 5-7 cm panel; curves about 0.3 mm wide are told apart, in"
                   " order, about two line widths apart (0.004-0.006 a0)")
W_C = Resolution(0.5, "m", "Figs. 2, 3a mark W_c by a dot on a 42 m axis (>= 3 m per cm): a"
                 " dot placed to about 1.5 mm, a floe length")
X_OVER_W_C = Resolution(0.04, "", "0.5 m (W_C) against W_c >= 14 m")
RATE_RATIO = Resolution(0.1, "", "Fig. 2's dashed lines (eq. 25 from the dot) against the"
                        " curves: a rate off by r moves a/a0 over the compact zone by about"
                        " (a/a0)^2 a0 alpha L r ~ 0.05 r (ml, eps 0.6), so r below ~0.1 moves"
                        " it less than A_REL")
ALPHA = Resolution(0.03, "m^-2", "a slope of 1/a changed by d alpha over a zone of ~20 m moves"
                   " a/a0 by about (a/a0)^2 a0 20 m d alpha ~ 0.17 m^2 d alpha: A_REL at 0.03")
DECADE = Resolution(0.1, "decade", "Fig. 3b-d: time-mean forces read across panels; the text"
                    " weighs them in orders of magnitude. Chosen, not measured: a factor 1.26")
EXPONENT = Resolution(0.1, "", "the text gives exponents as omega^4 and 2-2.5 (its fits 1.994,"
                      " 2.397): to a tenth at best")
SPIKES = Resolution(0.1, "per period", "Fig. 4's time series: one spike more or less in ten"
                    " periods. Chosen, not measured")
S_SD_RATIO = Resolution(0.05, "", "Fig. 4: the far floe's |S_sd| against the near one's on one"
                        " axis scaled to the spikes. Chosen, not measured")
DRIFT = Resolution(0.5, "m", "text only (no figure): a drift of less than a floe length would"
                   " not be called one")


@dataclass(frozen=True)
class Reading:
    """One sentence of the paper and the rows (``claims``, exactly as the table has them)
    that read it. ``testable`` False: the row reports a value the paper's data do not fix
    (an inconclusive row then reads "not testable")."""

    claims: tuple[str, ...]
    quote: str
    where: str
    reading: str
    resolution: Resolution
    testable: bool = True


def _both(claim: str, *tags: str) -> tuple[str, ...]:
    return tuple(f"{claim} ({t})" for t in tags)


_DF = "when df decreases, attenuation increases"
_ALPHA_TAIL = "with roughly ω2–ω2.5 damping in continuous ice or fields of large ice floes"

#: Every row's reading (the table's claims, each in exactly one).
READINGS: tuple[Reading, ...] = (
    Reading(_both("higher eps -> lower a/a0", "ml", "ep"),
            "the higher the ε, the lower the wave amplitude", "§4.2, Fig. 2",
            "a_end/a0 falls at every step of eps 0.2-0.8", A_REL),
    Reading(_both("higher eps -> narrower collisional zone W_c", "ml", "ep"),
            "The width of the collisional zone at the ice edge decreases with increasing ε",
            "§4.2, Figs. 2, 3a", "W_c falls at every step of eps 0.2-0.8", W_C),
    Reading(("ep attenuates less than ml (all else equal)",),
            "the EP dispersion relation will always lead to lower attenuation rates than ML",
            "§4.2, Figs. 2, 5", "a_end/a0 of ep above ml at each eps (Fig. 2), each L_x"
            " (Fig. 5)", A_REL),
    Reading(_both("smaller floes attenuate more", "ep", "ml"),
            "at least two mechanisms contribute to stronger attenuation when ice floes are"
            " small", "§4.2, Fig. 5", "a_end/a0 rises at every step of L_x 0.5-3 m", A_REL),
    Reading(("smaller d_f attenuates more near the edge",
             "smaller d_f attenuates more near the edge (long waves, d_f scan)"),
            _DF, "§4.2, Fig. 6a", "a/a0 at 5 m rises at every step of d_f (the paper's 5-50"
            " mm; the scan also 2, 3, 7.5, 15, 30 mm, outside or between them)", A_REL),
    Reading(("Fig. 6a reversal: far downwave smaller d_f attenuates less (short waves)",),
            "further down-wave, the relationship between df and a∕a0 reverses",
            "§4.2, Fig. 6a", "T 1.2 s: a_end/a0 falls at every step of d_f", A_REL),
    Reading((NO_REVERSAL,),
            "no analogous effect is present for the longer waves with T=1.8 s",
            "§4.2, Fig. 6a", "T 1.8 s: every d_f step of a/a0 has the same sign at 5 m as at"
            " the far end (no step flips; was: a_end/a0 rises with d_f)", A_REL),
    Reading(("larger a0 -> lower a/a0 (attenuation rate a0 alpha_c, eq. 25)",),
            "the modelled wave attenuation in both regions is strongly dependent on the"
            " incident wave amplitude a0", "§4.2, Fig. 6b",
            "a/a0 falls at every step of a0, at 5 m and at the far end (direction: eq. 25)",
            A_REL),
    Reading(_both("inner zone attenuates like confined ice", "ml", "ep"),
            "the simulated attenuation rates in the down-wave high-concentration region are"
            " very close to those computed analytically for motionless ice",
            "§4.2, Fig. 2", "alpha_inner / alpha_c in [0.8, 1.25]", RATE_RATIO),
    Reading(("Fig. 3: drag about two orders of magnitude below the wave force (compact"
             " zone)",), "with drag force roughly 2 orders of magnitude lower",
            "§4.2, Fig. 3b-d", "median log10(F_w/F_d) over the compact zone in [1.5, 2.5]",
            DECADE),
    Reading(("Fig. 3: drag a larger part of the balance near the edge",),
            "it contributes a significantly larger part to the overall force balance",
            "§4.2, Fig. 3b-d", "log10(F_w/F_d) lower in the collisional zone than in the"
            " compact one, at each eps", DECADE),
    Reading(_both("attenuation steep near the edge, flatter downwave", "ml", "ep"),
            "is large close to the ice edge, within a relatively narrow zone of very strong"
            " attenuation, and becomes smaller further down-wave", "§4.2, Fig. 2",
            "alpha_edge (x < W_c) above alpha_inner at each eps", ALPHA),
    Reading(_both("the rate reaches the compact zone's at W_c", "ml", "ep"),
            "the above-mentioned change of slope of the a(x) curve corresponds to the"
            " location of the boundary between those two regions", "§4.2, Figs. 2, 3a",
            "x_r / W_c in [0.8, 1.25], x_r where the local slope of 1/a has come down to"
            " 1.25 alpha_inner: Fig. 2 draws eq. 25 from each W_c dot (one reading: the"
            " two-line knot, mid-bend, is evidence only)", X_OVER_W_C),
    Reading((BALANCE,), "the wave-induced forces are balanced by the contact forces",
            "§4.2, Fig. 3b-c", "median log10(F_c/F_w) over the compact zone within 0.5"
            " decade of 0: the sentence weighs forces in orders of magnitude ('roughly 2"
            " orders', read 2 ± 0.5); it states no tighter bound (was: [0.8, 1.25])", DECADE),
    Reading(("downwave the attenuation rate is close to a0 alpha_c at every a0",),
            "the attenuation rate is close to a0αc", "§4.2, Fig. 6b; eq. 25",
            "alpha_inner / alpha_c in [0.8, 1.25] at every a0 with a compact zone",
            RATE_RATIO),
    Reading(("alpha_c (eq. 24) ~ omega^4 for ow",), "is proportional to ω4", "§3, eq. 27",
            "the exponent of alpha_c (ow) in [3.5, 4.5] (exact)", EXPONENT),
    Reading(("alpha_c (eq. 24) grows faster with omega for ml than for ow",),
            "the mass loading model predicts a faster-than-ω4 increase", "§3, eq. 28, Fig. 1b",
            "m(ml) > m(ow) (exact)", EXPONENT),
    Reading(("alpha_c (eq. 24) ~ omega^m, m 2-2.5, high-frequency tail, ep (field ice)",),
            _ALPHA_TAIL, "§3, Fig. 1b", "the tail's exponent (0.5-2 Hz) in [2.0, 2.5]"
            " (exact)", EXPONENT),
    Reading(("alpha_c (eq. 24) ~ omega^m, m 2-2.5, high-frequency tail, ep (lab ice)",),
            _ALPHA_TAIL, "§3, Fig. 1b", "as the field ice's, for an assumed lab ice: the"
            " paper does not give its ice (LS-WICE series 3000)", EXPONENT, testable=False),
    Reading(_both("alpha_inner (DEM) ~ omega^m with alpha_c's m over the same periods",
                  "ow", "ml", "ep") + ("alpha_inner (DEM) grows faster with omega for ml than"
                                       " for ow",),
            "the expected attenuation rates within that zone should be close to those"
            " computed analytically", "§5", "m - m_c in [-0.5, 0.5] over the same ten"
            " periods; m(ml) > m(ow)", EXPONENT),
    Reading(("near the edge S_sd spikes about once per period (after each collision)",),
            "large spikes in Ssd occur regularly after each collision", "§4.2, Fig. 4",
            "excursions of |S_sd| above 3 x median at 3 m, per period, in [0.8, 1.25]",
            SPIKES),
    Reading(("far from the edge S_sd is low",),
            "Floes far from the ice edge experience very low, periodically varying Ssd"
            " values", "§4.2, Fig. 4", "time-mean S_sd at 30 m below 0.1 of that at 3 m",
            S_SD_RATIO),
    Reading(("random initial locations have no influence on the results",),
            "this aspect of the set-up has no influence on the results", "§4.1",
            "|a_end/a0 (uniform) - a_end/a0 (fig2)| < 0.01 (the campaigns' resolution)",
            A_REL),
    Reading(tuple(spring_claim(w) for w in ("k_s / 10", "k_s x 10")),
            "the value of ks does not have visible results on the simulated attenuation, of"
            " interest in this study", "§4.1", "|a_end/a0 (k_s changed) - a_end/a0 (fig2)|"
            f" < {A_RESOLUTION:g}, what a figure of a/a0 could show (was: < 0.01)", A_REL),
    Reading(("without the edge spring the floes drift upwave",),
            "the floes drift gradually in the up-wave direction", "§4.2, §5",
            "the first floe's mean centre upwave of its start (k_s = 0)", DRIFT),
)

#: The claims of the v8 settling read otherwise since: old claim -> (the claim that reads
#: its sentence now, ``"re-read"``: the same pooled estimates read with the new rule, or
#: ``"merged"``: one reading of a sentence two rows read).
REWRITTEN: dict[str, tuple[str, str]] = {
    "Fig. 6a: no reversal for long waves (collisional zone spans the domain)":
        (NO_REVERSAL, "re-read"),
    "the rate changes at W_c (ml)": ("the rate reaches the compact zone's at W_c (ml)",
                                     "merged"),
    "the rate changes at W_c (ep)": ("the rate reaches the compact zone's at W_c (ep)",
                                     "merged"),
    "Fig. 3: in the compact zone the wave force is balanced by contact forces":
        (BALANCE, "re-read"),
    "the edge spring constant has no visible effect (k_s / 10)":
        (spring_claim("k_s / 10"), "re-read"),
    "the edge spring constant has no visible effect (k_s x 10)":
        (spring_claim("k_s x 10"), "re-read"),
}

_BY_CLAIM = {c: r for r in READINGS for c in r.claims}


def reading_of(claim: str) -> Reading | None:
    """The reading of the row with this claim (a rewritten v8 claim: its new reading)."""
    return _BY_CLAIM.get(REWRITTEN.get(claim, (claim, ""))[0])


def missing_quotes(text: str) -> list[str]:
    """The readings' quotes that are not verbatim in ``text`` (the paper's published text:
    ``python -c "import sys, herman2019.readings as r; print(r.missing_quotes(open(sys.argv[1]).read()))" PAPER.txt``
    prints ``[]`` when every quote is the paper's)."""
    return [r.quote for r in READINGS if r.quote not in text]
