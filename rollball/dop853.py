"""Dormand–Prince 8(5,3) ("DOP853") as data, checked against its order conditions when built.

E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*, 2nd ed.,
Springer 1993, §II.10, and the coefficients of Hairer's Fortran code dop853.f (also used by
scipy's DOP853). Twelve stages give the 8th-order step; stage 13 (index 12) is the
derivative at the new state. The error of a step is estimated from two embedded
estimates, of orders 5 (weights ``E5``: b − b̂₅) and 3 (weights ``BHH``: b̂₃), combined as
in dop853.f. Three more stages (14–16) give the 7th-order dense output.

The coefficients are the published decimals, kept exactly (``Decimal`` of the text) and
checked in 60-digit arithmetic: the order conditions hold to the digits given (~1e-28), and
``DensePair`` refuses, when built, coefficients whose residuals exceed ``RESIDUAL_LIMIT``.
"""

from __future__ import annotations

from dataclasses import dataclass
from decimal import Decimal, localcontext

import numpy as np

from .kinds import MethodInfo, MethodKind
from .order_conditions import ElementaryWeights, residuals, size

C = (
    "0.0",
    "0.526001519587677318785587544488e-01",
    "0.789002279381515978178381316732e-01",
    "0.118350341907227396726757197510",
    "0.281649658092772603273242802490",
    "0.333333333333333333333333333333",
    "0.25",
    "0.307692307692307692307692307692",
    "0.651282051282051282051282051282",
    "0.6",
    "0.857142857142857142857142857142",
    "1.0",
    "1.0",
    "0.1",
    "0.2",
    "0.777777777777777777777777777778",
)

A = {
    1: {0: "5.26001519587677318785587544488e-2"},
    2: {0: "1.97250569845378994544595329183e-2", 1: "5.91751709536136983633785987549e-2"},
    3: {0: "2.95875854768068491816892993775e-2", 2: "8.87627564304205475450678981324e-2"},
    4: {0: "2.41365134159266685502369798665e-1", 2: "-8.84549479328286085344864962717e-1",
        3: "9.24834003261792003115737966543e-1"},
    5: {0: "3.7037037037037037037037037037e-2", 3: "1.70828608729473871279604482173e-1",
        4: "1.25467687566822425016691814123e-1"},
    6: {0: "3.7109375e-2", 3: "1.70252211019544039314978060272e-1",
        4: "6.02165389804559606850219397283e-2", 5: "-1.7578125e-2"},
    7: {0: "3.70920001185047927108779319836e-2", 3: "1.70383925712239993810214054705e-1",
        4: "1.07262030446373284651809199168e-1", 5: "-1.53194377486244017527936158236e-2",
        6: "8.27378916381402288758473766002e-3"},
    8: {0: "6.24110958716075717114429577812e-1", 3: "-3.36089262944694129406857109825",
        4: "-8.68219346841726006818189891453e-1", 5: "2.75920996994467083049415600797e1",
        6: "2.01540675504778934086186788979e1", 7: "-4.34898841810699588477366255144e1"},
    9: {0: "4.77662536438264365890433908527e-1", 3: "-2.48811461997166764192642586468",
        4: "-5.90290826836842996371446475743e-1", 5: "2.12300514481811942347288949897e1",
        6: "1.52792336328824235832596922938e1", 7: "-3.32882109689848629194453265587e1",
        8: "-2.03312017085086261358222928593e-2"},
    10: {0: "-9.3714243008598732571704021658e-1", 3: "5.18637242884406370830023853209",
        4: "1.09143734899672957818500254654", 5: "-8.14978701074692612513997267357",
        6: "-1.85200656599969598641566180701e1", 7: "2.27394870993505042818970056734e1",
        8: "2.49360555267965238987089396762", 9: "-3.0467644718982195003823669022"},
    11: {0: "2.27331014751653820792359768449", 3: "-1.05344954667372501984066689879e1",
        4: "-2.00087205822486249909675718444", 5: "-1.79589318631187989172765950534e1",
        6: "2.79488845294199600508499808837e1", 7: "-2.85899827713502369474065508674",
        8: "-8.87285693353062954433549289258", 9: "1.23605671757943030647266201528e1",
        10: "6.43392746015763530355970484046e-1"},
    12: {0: "5.42937341165687622380535766363e-2", 5: "4.45031289275240888144113950566",
        6: "1.89151789931450038304281599044", 7: "-5.8012039600105847814672114227",
        8: "3.1116436695781989440891606237e-1", 9: "-1.52160949662516078556178806805e-1",
        10: "2.01365400804030348374776537501e-1", 11: "4.47106157277725905176885569043e-2"},
    13: {0: "5.61675022830479523392909219681e-2", 6: "2.53500210216624811088794765333e-1",
        7: "-2.46239037470802489917441475441e-1", 8: "-1.24191423263816360469010140626e-1",
        9: "1.5329179827876569731206322685e-1", 10: "8.20105229563468988491666602057e-3",
        11: "7.56789766054569976138603589584e-3", 12: "-8.298e-3"},
    14: {0: "3.18346481635021405060768473261e-2", 5: "2.83009096723667755288322961402e-2",
        6: "5.35419883074385676223797384372e-2", 7: "-5.49237485713909884646569340306e-2",
        10: "-1.08347328697249322858509316994e-4", 11: "3.82571090835658412954920192323e-4",
        12: "-3.40465008687404560802977114492e-4", 13: "1.41312443674632500278074618366e-1"},
    15: {0: "-4.28896301583791923408573538692e-1", 5: "-4.69762141536116384314449447206",
        6: "7.68342119606259904184240953878", 7: "4.06898981839711007970213554331",
        8: "3.56727187455281109270669543021e-1", 12: "-1.39902416515901462129418009734e-3",
        13: "2.9475147891527723389556272149", 14: "-9.15095847217987001081870187138"},
}

E5 = {0: "0.1312004499419488073250102996e-1", 5: "-0.1225156446376204440720569753e+1",
      6: "-0.4957589496572501915214079952", 7: "0.1664377182454986536961530415e+1",
      8: "-0.3503288487499736816886487290", 9: "0.3341791187130174790297318841",
      10: "0.8192320648511571246570742613e-1", 11: "-0.2235530786388629525884427845e-1"}

BHH = {0: "0.244094488188976377952755905512", 8: "0.733846688281611857341361741547",
       11: "0.220588235294117647058823529412e-1"}

D = (
    {0: "-0.84289382761090128651353491142e+1", 5: "0.56671495351937776962531783590",
     6: "-0.30689499459498916912797304727e+1", 7: "0.23846676565120698287728149680e+1",
     8: "0.21170345824450282767155149946e+1", 9: "-0.87139158377797299206789907490",
     10: "0.22404374302607882758541771650e+1", 11: "0.63157877876946881815570249290",
     12: "-0.88990336451333310820698117400e-1", 13: "0.18148505520854727256656404962e+2",
     14: "-0.91946323924783554000451984436e+1", 15: "-0.44360363875948939664310572000e+1"},
    {0: "0.10427508642579134603413151009e+2", 5: "0.24228349177525818288430175319e+3",
     6: "0.16520045171727028198505394887e+3", 7: "-0.37454675472269020279518312152e+3",
     8: "-0.22113666853125306036270938578e+2", 9: "0.77334326684722638389603898808e+1",
     10: "-0.30674084731089398182061213626e+2", 11: "-0.93321305264302278729567221706e+1",
     12: "0.15697238121770843886131091075e+2", 13: "-0.31139403219565177677282850411e+2",
     14: "-0.93529243588444783865713862664e+1", 15: "0.35816841486394083752465898540e+2"},
    {0: "0.19985053242002433820987653617e+2", 5: "-0.38703730874935176555105901742e+3",
     6: "-0.18917813819516756882830838328e+3", 7: "0.52780815920542364900561016686e+3",
     8: "-0.11573902539959630126141871134e+2", 9: "0.68812326946963000169666922661e+1",
     10: "-0.10006050966910838403183860980e+1", 11: "0.77771377980534432092869265740",
     12: "-0.27782057523535084065932004339e+1", 13: "-0.60196695231264120758267380846e+2",
     14: "0.84320405506677161018159903784e+2", 15: "0.11992291136182789328035130030e+2"},
    {0: "-0.25693933462703749003312586129e+2", 5: "-0.15418974869023643374053993627e+3",
     6: "-0.23152937917604549567536039109e+3", 7: "0.35763911791061412378285349910e+3",
     8: "0.93405324183624310003907691704e+2", 9: "-0.37458323136451633156875139351e+2",
     10: "0.10409964950896230045147246184e+3", 11: "0.29840293426660503123344363579e+2",
     12: "-0.43533456590011143754432175058e+2", 13: "0.96324553959188282948394950600e+2",
     14: "-0.39177261675615439165231486172e+2", 15: "-0.14972683625798562581422125276e+3"},
)

ORDER, ORDER_5, ORDER_3, DENSE_ORDER = 8, 5, 3, 7
STAGES = 12                 # the 8th-order step; stage 13 is the derivative at the new state
ALL_STAGES = len(C)         # with the three stages of the dense output
RESIDUAL_LIMIT = 1e-20      # the published decimals meet every condition far below this


PRECISION = 60              # digits of the arithmetic that checks the conditions
ZERO = Decimal(0)


def _dense_weights(b, D) -> list[list[Decimal]]:
    """P with y(t + x h) = y + h sum_i K_i sum_k P[i][k] x^(k+1), from dop853.f's form
    y + x (F0 + (1-x) (F1 + x (F2 + (1-x) (F3 + x (F4 + (1-x) (F5 + x F6)))))), where
    F0 = h sum b_i K_i, F1 = h K_1 - F0, F2 = 2 F0 - h (K_1 + K_13), F3.. = h D K."""
    s = ALL_STAGES
    f0 = list(b) + [ZERO] * (s - len(b))
    f1 = [(1 if i == 0 else 0) - f0[i] for i in range(s)]
    f2 = [2 * f0[i] - (1 if i in (0, STAGES) else 0) for i in range(s)]
    factors = [f0, f1, f2] + [[d.get(i, ZERO) for i in range(s)] for d in D]
    # the multiplier of F_j: x^(j//2 + 1) (1 - x)^((j + 1)//2), as coefficients of x^0 .. x^7
    P = [[ZERO] * DENSE_ORDER for _ in range(s)]
    for j, f in enumerate(factors):
        poly = [ZERO] * (j // 2 + 1) + [Decimal(1)]
        for _ in range((j + 1) // 2):
            poly = [a - b for a, b in zip(poly + [0], [0] + poly)]
        for i in range(s):
            if f[i]:
                for k in range(1, len(poly)):
                    P[i][k - 1] += f[i] * poly[k]
    return P


@dataclass(frozen=True)
class DensePair(MethodInfo):
    """DOP853 as exact numbers, checked when built: an explicit embedded pair with dense output.

    ``A`` is square over all stages (strictly lower triangular; the rows after ``STAGES``
    are the dense output's extra stages), ``b`` the weights of the ``STAGES`` stages,
    ``e5`` and ``e3`` the error weights of the two estimates over the stages and the
    derivative at the new state, ``P`` the dense-output weights (stage x power of x).
    """

    c: tuple
    A: tuple
    b: tuple
    e5: tuple
    e3: tuple
    P: tuple

    name = "dop853"
    label = "DOP853"
    order = ORDER
    kind = MethodKind.ADAPTIVE
    stages = STAGES + 1          # with the derivative at the new state ("first same as last")
    # the combined estimate err5^2 / sqrt(err5^2 + err3^2 / 100) behaves like an estimate of
    # order 7: dop853.f's (and scipy's) step-size exponent -1/8
    error_exponent = -1.0 / 8.0

    def __post_init__(self):
        with localcontext() as context:
            context.prec = PRECISION
            self._check()

    def _check(self):
        s, A = len(self.c), self.A
        if any(A[i][j] for i in range(s) for j in range(i, s)):
            raise ValueError("DOP853: the stage matrix is not strictly lower triangular")
        for i in range(s):
            if abs(sum(A[i]) - self.c[i]) > RESIDUAL_LIMIT:
                raise ValueError(f"DOP853: row {i + 1} of A does not sum to c[{i + 1}]")
        if tuple(A[STAGES][:STAGES]) != self.b or any(A[STAGES][STAGES:]):
            raise ValueError("DOP853: stage 13 must be the new state (its row of A is b)")
        b_hat5 = [bi - ei for bi, ei in zip(self.b, self.e5)]
        b_hat3 = [bi - ei for bi, ei in zip(self.b, self.e3)]
        if self.e5[STAGES] or self.e3[STAGES]:
            raise ValueError("DOP853: the error estimates do not use the derivative at the new state")
        phi = ElementaryWeights(A)
        for weights, order, what in ((self.b, ORDER, "b"), (b_hat5, ORDER_5, "the 5th-order estimate"),
                                     (b_hat3, ORDER_3, "the 3rd-order estimate")):
            for tree, residual in residuals(A, weights, order, phi):
                if abs(residual) > RESIDUAL_LIMIT:
                    raise ValueError(f"DOP853: {what} fails the order condition of the tree {tree} "
                                     f"(order {size(tree)}) by {float(residual):.3g}")
        for k in range(DENSE_ORDER):  # the dense output, power by power of x
            weights = [row[k] for row in self.P]
            for tree, residual in residuals(A, weights, DENSE_ORDER, phi, power=k + 1):
                if abs(residual) > RESIDUAL_LIMIT:
                    raise ValueError(f"DOP853: the dense output fails the order condition of "
                                     f"the tree {tree} at x^{k + 1} by {float(residual):.3g}")

    @property
    def last(self) -> int:
        """Index of the derivative at the new state among the stage derivatives K."""
        return STAGES

    interpolation_order = DENSE_ORDER

    def dense_output(self) -> tuple[tuple[Decimal, ...], ...]:
        """The interpolation matrix P: z(t + x h) = z + h sum_i K_i sum_k P[i][k] x^(k+1)."""
        return self.P

    def kernel_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(W, E, P) as kernel.loops.advance_adaptive reads them: W the stage matrix over all
        sixteen stages (row 12, the derivative at the new state, is b; rows 13 .. 15 the dense
        output's stages), E the two error estimates over stages 0 .. 12, P the dense output."""
        def floats(rows):
            return np.array([[float(v) for v in row] for row in rows])

        return floats(self.A), floats((self.e5, self.e3)), floats(self.P)


def build(c=C, a=A, e5=E5, bhh=BHH, d=D) -> DensePair:
    """The pair from its published decimals (the arguments are for tests that alter one)."""
    with localcontext() as context:
        context.prec = PRECISION
        return _build(c, a, e5, bhh, d)


def _build(c, a, e5, bhh, d) -> DensePair:
    s = ALL_STAGES
    A_ = [[Decimal(a[i][j]) if i in a and j in a[i] else ZERO for j in range(s)] for i in range(s)]
    b = tuple(A_[STAGES][:STAGES])
    e5_ = tuple(Decimal(e5.get(i, "0")) for i in range(STAGES + 1))
    e3_ = tuple(b[i] - Decimal(bhh.get(i, "0")) for i in range(STAGES)) + (ZERO,)
    D_ = [{i: Decimal(v) for i, v in row.items()} for row in d]
    P = _dense_weights(b, D_)
    return DensePair(tuple(Decimal(v) for v in c), tuple(tuple(r) for r in A_), b, e5_, e3_,
                     tuple(tuple(r) for r in P))


DOP853 = build()
