"""The linear-algebra wing: how a least-squares formulation is factored and inverted.

- :mod:`bvpnav.linalg.lsq`: the equality-constrained least-squares view of a formulation
  (:class:`~bvpnav.linalg.lsq.LeastSquaresForm`), the forward-error check, the bordered
  sparse factorizations, the band plan and the direct solve;
- :mod:`bvpnav.linalg.banded`: the KKT system as a banded matrix with a border (O(N));
- :mod:`bvpnav.linalg.ipm`: bands and inequalities by an interior-point method whose every
  step is one banded factorization (the direct back end's path for them);
- :mod:`bvpnav.linalg.condensed`: the band condensed to the nodes a lambda sweep reads;
- :mod:`bvpnav.linalg.selinv`: selected inversion of block-tridiagonal matrices;
- :mod:`bvpnav.linalg.covariance`: the posterior covariance of a solution.

The wing sits above :mod:`bvpnav.formulation` (what the problem is) and below the solve
layer (:mod:`bvpnav.backends`, :mod:`bvpnav.lam`, :mod:`bvpnav.solve`); :mod:`bvpnav.model`
and :mod:`bvpnav.terms` import nothing from it.
"""
