"""Table 2 of Meijaard et al. 2007 as comparisons/judgments/published.py hands it out: four
complex eigenvalues per speed in `linearize`'s sort order (the docstring's contract). The
expected layout is written out from the paper's table (v = 0: four real roots; above: the weave
pair re +- im i, then capsize and castor). Pure, ~1 ms."""

import numpy as np

from comparisons.judgments.published import MEIJAARD_TABLE2, table2_eigenvalues


def test_every_speed_gives_four_complex_eigenvalues_in_sort_order():
    for v, (a, b, c, d) in MEIJAARD_TABLE2.items():
        lam = table2_eigenvalues(v)
        assert lam.dtype == np.complex128 and lam.shape == (4,), v
        if v == 0:
            assert lam.tolist() == [complex(a), complex(b), complex(c), complex(d)]
        else:
            assert lam.tolist() == [complex(a, b), complex(a, -b), complex(c), complex(d)]
    # v = 0 by hand: 5.53..., 3.13..., -3.13..., -5.53... (the paper's first row)
    assert table2_eigenvalues(0)[0] == 5.53094371765393 + 0j
    assert table2_eigenvalues(4)[1] == 0.41325331521125 - 3.07910818603206j
