"""Benchmark: bvpnav's back ends beside an O(N) banded reference, in the same process (issue 18).

The reference (:mod:`_banded_reference`, ~60 lines of numpy + LAPACK ``dgbtrf``/``dgbtrs``)
solves exactly the KKT system bvpnav solves, with the acceleration residual eliminated
(``w = -sigma_a^2 M mu``), the unknowns interleaved as ``(r_j, mu_j)`` (banded, kl = ku = 4)
and the end velocities, the hard rows' multipliers and the error-model parameters
bordered (one banded factor, ``1 + border`` right-hand sides, a small Schur complement).

Problems (100 Hz, ``t = 0.01 k`` s, a smooth acceleration ``A sin(w t + phi)`` plus a
constant 2 m/s drift in position, accelerometer noise 0.05 m/s^2 with ``sigma_a = 0.05``):

- soft position fixes (GNSS-like) every 1 s at half-sample times (``0.505 + k`` s, so they
  interpolate between two nodes), 1 m noise, ``sigma = 1`` m, weighted by lambda;
- both end positions hard (surveyed start and end);
- soft velocities at the two ends (0.05 m/s noise, ``sigma = 0.05`` m/s, weighted by
  lambda). Interior velocity fixes are left out on purpose: a velocity at an interior
  node depends on ``w``, which the reference eliminates;
- (a) one axis; (b) three axes with ``ScaleFactor() + Bias()`` (scale errors 1 %, -2 %,
  0.5 %; biases 0.05, -0.03, 0.02 m/s^2): six parameters in the border.

Rows (``speed`` table): for each case and N, every variant is timed in the same process,
the variants interleaved, ``--repeat`` times (median of the per-repetition ratios to the
reference; at N >= 1e6 the reference, ``direct``, its back end and the Clarabel rows are
repeated, ``csne`` runs once and is divided by the median reference time; a Clarabel row's
note gives its first run's time too: the first solve of that size in the process may pay
for faulting in fresh memory, 14.8 s against 6.7 s for the next at 1e6 on one VM):
``direct`` as a user calls it
(``prob.solve(solver="direct")`` on a freshly built problem), ``direct back end`` (the
back end's ``run`` alone, items compiled beforehand: no verification, no ``Solution``),
``csne``, ``clarabel`` (first solve; cvxpy's compile time reported separately) and its
DPP re-solve at ``lam = 2`` (the cached problem), ``osqp`` at N = 1e4 only (one run,
unverified). Every answer: the max-norm difference of the trajectory from the reference
relative to its max-norm, and bvpnav's own ``stats["verified"]``.

``lambda`` table: ``prob.solve(solver="direct", lam=rule)`` for ``lcurve``, ``gcv``,
``quasi`` at N = 1e5 (1 axis; ``--lam-huge`` adds 1e6), the median of three runs, as
multiples of a single direct solve: each run beside a single solve, the median of the
three ratios (before the eleventh session the single solves were all timed first), the
number of evaluations and the lambda chosen.

``memory`` table (``--memory``): one child process per row (``_memory.py``, VmHWM) at
``--memory-n`` (1e6): a baseline child (imports, data, the problem with its items, no
solve), then the reference, ``direct``, ``csne`` and ``clarabel`` (1 axis); MB and bytes
per sample above the baseline.

``peers`` table: ``bvpnav.baselines.rts_smoother`` and, where installed, filterpy's and
pykalman's Kalman filter + RTS smoother on the same 1-axis measurements (a different
model: per-sample white acceleration noise; for orientation only, times and the
difference from the reference).

``--huge``: 1e7 samples x 1 axis with ``direct`` in a child process capped at
``--huge-cap`` GB of address space (RLIMIT_AS), peak memory reported (or why it failed).

BLAS runs on one thread (threadpoolctl when installed; the ``*_NUM_THREADS`` variables are
set before numpy is imported either way). Timings belong here, never in tests.

Measurements behind the design of :mod:`bvpnav.linalg` and the formulation, moved here from
their code comments (each taken once, on one VM, in the session that made the change):

- ``BandPlan._scatter`` (``SCATTER_SLICE``): 2e6 band rows, eleven strided diagonals: 56 ms
  by slices of 8192 rows (0.85 MB of a band with kl = 4), 98 ms by 65536, 213 ms whole; one
  diagonal at a time would stream the whole band once per diagonal (208 MB at N = 1e6).
- ``_Stride`` copies: a slice copy of 2e5 doubles 0.04 ms, numpy's fancy indexing with int32
  positions 0.4 ms (gather) and 0.66 ms (scatter).
- ``KeptFactors.buffer``: writing the chosen lambda's band into memory the sweep touched saves
  the page faults of a first write, about 20 ms at N = 1e5 and 200 ms at 1e6.
- Fresh memory avoided, three axes at N = 1e6 (six parameters where bordered): the in-place
  residual of ``AugmentedOperator`` (96 MB per full-length array), its ``max_abs`` (a copy of
  ``|E|``, 192 MB), the boolean column marks of the plan (two counts: 96 MB), the border's
  blocks instead of dense ``(nb, k)`` copies of ``B`` or ``X`` (288 MB each), the run blocks
  kept as views (210 MB), the reduced right-hand side solved in place (72 MB per solve).
- The plan's node sort by one combined key: 5.2 -> 3.5 ms against lexsort at N = 1e5; scipy's
  column indexing of ``E`` 2.0 ms against 3.3 ms for the product with a selection matrix at 1e5.
- ``least_squares_form``: a hard item's explicit zero copied the whole FEM block (60 ms at
  N = 1e6) before each part was made canonical before stacking.
- ``BANDED_TOL``: at lambda = 0.005 on 1e5 samples the first refinement correction was 4.2e-10
  and a second one, 1.0e-11, only showed the rounding floor.
- ``Formulation._null_columns``: a dense ``(n, 2 d + q)`` array was 58 MB and 0.1 s at N = 1e5
  on three axes with six parameters (12 million entries on three axes at N = 1e6).
- ``csne`` without the parameters' Schur complement: the LU filled in to 8.8 GB and counting on
  a three-axis, nine-parameter problem of 12,000 samples.
- ``cvxpy.installed_solvers()`` (cached by the back-end table): about 3 ms per call.

Flags: ``--quick`` (N = 2e3 and 1e4, seconds), ``--sizes`` (1-axis N, default 1e4,1e5,1e6),
``--sizes3`` (3-axis N, default the same), ``--repeat`` (3; the speed and lambda tables),
``--skip`` (comma-separated variants to leave out, e.g. ``csne3@1e6,clarabel3@1e6``; ``name@N``
or ``name`` for all N; ``name3`` for the 3-axis case), ``--lam-n`` (1e5), ``--lam-huge``, ``--no-lam``,
``--memory``, ``--memory-n``, ``--no-peers``, ``--huge``, ``--huge-cap``, ``--huge-n``, ``--osqp-max``,
``--profile N`` (only a cProfile of one ``direct`` solve at N; ``--profile-axes``)
(1e4; 2e3 with ``--quick``).

Run ``python examples/benchmarks/speed_memory.py [--quick] [--memory] [--huge]``.

Measured after the fresh-memory diet (issue 18, eleventh session)
-----------------------------------------------------------------
2026-12-04, main at 0b0847e, ``--sizes 1e4,1e5,1e6 --sizes3 1e5,1e6 --skip
csne@1e6,csne3@1e6,clarabel3@1e6 --lam-huge --memory --huge --no-peers``, on the tenth
session's VM. perf showed 41 % of a three-axis run's samples in the kernel clearing fresh
pages (``clear_page_erms``; the VM reports freed pages to its host): a direct solve at
three axes and N = 1e6 mapped 4.78 GB of fresh memory (strace), the reference 1.74 GB.
The session cut it to 3.10 GB (M G by its acting columns, the equality rows written
once, |A| |x| by blocks, one residual buffer, the reduced right-hand side solved in
place, the stationarity from row weights, ...) and some arithmetic (uniform stretches of
rows as 2-D slices, the band's scales in place, K's and M's diagonals kept); the lambda
table now times each rule beside a single solve::

    case               N  variant              time s   x ref runs     vs ref  verified
    1 ax          100000  direct                0.119     1.7    3    1.4e-12  True
    1 ax          100000  direct backend        0.095     1.1    3    1.4e-12  -
    1 ax          100000  clarabel              0.647     9.5    3    2.2e-12  True   compile 0.23 s
    1 ax          100000  clarabel re-solve     0.282     4.0    3    1.9e-12  True
    1 ax         1000000  direct                1.039     1.2    3    3.3e-12  True
    1 ax         1000000  direct backend        0.887     1.1    3    3.3e-12  -
    1 ax         1000000  clarabel              7.717     9.9    3    4.2e-12  True   compile 2.48, 1st 9.09 s
    1 ax         1000000  clarabel re-solve     3.152     4.8    3    2.9e-12  True
    3 ax +SF+B    100000  direct                0.386     2.0    3    2.5e-12  True
    3 ax +SF+B    100000  clarabel              2.645    12.8    3    2.5e-12  True   compile 1.00 s
    3 ax +SF+B    100000  clarabel re-solve     1.174     6.1    3    2.2e-12  True
    3 ax +SF+B   1000000  direct                4.619     2.0    3    3.3e-12  True
    3 ax +SF+B   1000000  direct backend        3.910     1.6    3    3.3e-12  -

    lambda rules, N = 100000: single direct solve 0.10 s (the reference 0.049 s)
    rule        lambda  evaluations  ms/eval  total s  x single   x ref
    lcurve    0.005152           12     28.2     0.40       4.2       8
    gcv         0.5475           13     29.7     0.50       5.3      10
    quasi        5.164           19     31.7     0.66       6.6      14

    lambda rules, N = 1000000: single direct solve 1.09 s (the reference 0.658 s)
    lcurve     0.01145           11    369.1     4.27       4.4       6
    gcv         0.7266           16    348.0     5.68       5.8       9
    quasi        3.234           19    374.1     7.63       6.8      12

    peak memory, N = 1e6: reference 745 MB, direct 1004 MB (1.35x; 855 B/sample above
    the base), csne 2058 MB, clarabel 3042 MB; 1e7 samples x 1 axis: 8326 MB, verified,
    37.4 s

Other runs of this session with the final code or near it: direct 1.6-2.0x at 1e5 and
1.2-1.9x at 1e6 (one axis), 1.8-2.2x and 2.0-2.9x (three axes); the session's starting
commit beside it 2.4-3.1x and 3.2-4.2x at 1e6. lcurve 4.2-4.7, gcv 4.6-5.3 single
solves at 1e5 timed beside them (4.3-5.2 and 4.5-6.7 with the single solves timed
first); Clarabel's three-axis re-solve at 1e5 4.8-6.1x. With glibc keeping freed memory
(``GLIBC_TUNABLES=glibc.malloc.mmap_max=0:glibc.malloc.trim_threshold=68719476736``) the
three-axis solve at 1e6 spends no time clearing pages: 1.85x against 2.69x in runs side
by side on a slow afternoon of the VM.

Measured after the condensed lambda sweep (issue 18, tenth session)
------------------------------------------------------------------
2026-12-04, main at 3686a19, ``--sizes 1e4,1e5,1e6 --sizes3 1e5,1e6 --skip
csne@1e6,csne3@1e6,clarabel3@1e6,clarabel@1e6 --lam-huge --memory --huge --no-peers``,
on the ninth session's VM ("AMD EPYC"), which ran slower this day: the reference took
0.070-0.077 s at 1e5 (0.042-0.068 s the day before), and the session's starting commit
d55a012 measured direct 2.3x at 1e6 in a run beside this one (1.8x the day before). The
lambda sweep condenses the band onto the unknowns lambda changes (``bvpnav.linalg.condensed``),
the L-curve steps by a degree-7 Hermite model (12 evaluations, was 14), GCV takes the
condensed log-determinant; the direct path is unchanged::

    case               N  variant              time s   x ref runs     vs ref  verified
    1 ax          100000  direct                0.111     1.6    3    1.4e-12  True
    1 ax          100000  direct backend        0.086     1.2    3    1.4e-12  -
    1 ax          100000  clarabel              0.626     8.3    3    2.2e-12  True   compile 0.20 s
    1 ax          100000  clarabel re-solve     0.272     3.9    3    1.9e-12  True
    1 ax         1000000  direct                1.941     2.3    3    3.3e-12  True
    1 ax         1000000  direct backend        1.071     1.3    3    3.3e-12  -
    3 ax +SF+B    100000  direct                0.446     2.2    3    2.5e-12  True
    3 ax +SF+B    100000  clarabel              2.652    13.4    3    2.5e-12  True   compile 1.04 s
    3 ax +SF+B    100000  clarabel re-solve     1.088     5.6    3    2.2e-12  True
    3 ax +SF+B   1000000  direct                9.162     3.4    3    3.3e-12  True
    3 ax +SF+B   1000000  direct backend        6.141     2.7    3    3.3e-12  -

    lambda rules, N = 100000: single direct solve 0.14 s (the reference 0.077 s)
    rule        lambda  evaluations  ms/eval  total s  x single   x ref
    lcurve    0.005152           12     40.2     0.57       4.1       7
    gcv         0.5475           13     31.4     0.52       3.7       7
    quasi        5.164           19     32.9     0.70       4.9       9

    lambda rules, N = 1000000: single direct solve 1.31 s (the reference 0.813 s)
    lcurve     0.01145           11    497.3     6.30       4.8       8
    gcv         0.7266           16    426.8     7.40       5.7       9
    quasi        3.234           19    509.6    10.62       8.1      13

    peak memory, N = 1e6: reference 745 MB, direct 1126 MB (1.51x; 984 B/sample above
    the base), csne 2108 MB, clarabel 3067 MB; 1e7 samples x 1 axis: 9292 MB, verified,
    44.2 s

Other runs of this session on the same VM: lcurve 3.9-4.2 and 3.7 at 1e6, gcv 3.2-3.6
and 4.8-5.5, quasi 4.7-6.5 and 6.1-6.2; direct 1.6-2.0x at 1e5 and 2.2x at 1e6, three
axes 3.4-3.5x at 1e6 (2.5x for d55a012 beside it, its reference 15 % slower in that
run). The L-curve's peak memory at 1e6 is 1.76 GB (1.60 GB before the condensation: the
interior's factor lives for the sweep). A condensed point at 1e5 costs a small ``dgbtrf``
(12,016 unknowns, bandwidth 6) and one ``dgbtrs`` with the interior's factor, about 28
ms with the set-up against 38-42 ms for a copy and a factorization of the whole band.

Measured on another CPU (issue 18, ninth session)
-------------------------------------------------
2026-12-04, main at 8ad269e, ``--skip csne3@1e6,clarabel3@1e6 --memory --huge``, on a VM
whose CPU reports "AMD EPYC" (32 MB L3, OpenBLAS's SkylakeX kernels); the eighth
session's table below came from another VM. The band rows move by slices, the refinement
stops at the preset's 1e-8, GCV samples every two decades with half-way points, the
data rows are scaled without a sparse product; Clarabel repeated at 1e6 (the note gives
the first run's time)::

    case               N  variant              time s   x ref runs     vs ref  verified
    1 ax          100000  direct                0.130     2.2    3    1.4e-12  True
    1 ax          100000  direct backend        0.095     1.6    3    1.4e-12  -
    1 ax          100000  clarabel              0.545    10.9    3    2.2e-12  True   compile 0.22 s
    1 ax          100000  clarabel re-solve     0.270     4.4    3    1.9e-12  True
    1 ax         1000000  direct                1.183     1.8    3    3.3e-12  True
    1 ax         1000000  direct backend        0.984     1.5    3    3.3e-12  -
    1 ax         1000000  clarabel              7.270    10.9    3    4.2e-12  True   compile 2.5, 1st 12.6 s
    1 ax         1000000  clarabel re-solve     2.950     4.0    3    2.9e-12  True
    3 ax +SF+B    100000  direct                0.324     2.0    3    2.5e-12  True
    3 ax +SF+B    100000  clarabel              2.094    12.7    3    2.5e-12  True   compile 0.75 s
    3 ax +SF+B    100000  clarabel re-solve     0.849     5.2    3    2.2e-12  True
    3 ax +SF+B   1000000  direct                6.908     2.9    3    3.3e-12  True
    3 ax +SF+B   1000000  direct backend        5.120     2.3    3    3.3e-12  -

    lambda rules, N = 100000: single direct solve 0.09 s (the reference 0.042 s)
    rule        lambda  evaluations  ms/eval  total s  x single   x ref
    lcurve    0.005152           14     35.4     0.55       6.1      13
    gcv         0.5475           13     41.6     0.60       6.7      14
    quasi        5.164           19     35.0     0.73       8.1      17

    peak memory, N = 1e6: reference 746 MB, direct 1111 MB (1.49x; 967 B/sample above
    the base), csne 2112 MB, clarabel 3057 MB (3007 B/sample); 1e7 samples x 1 axis:
    9215 MB, verified, 40.1 s

Other runs of this session on the same VM (code between d03b5c6 and aa45b5d): direct
1.8-2.0x at 1e5 and 1.9x at 1e6, three axes 2.2-2.4x and 2.6-3.1x; Clarabel run once at
1e6 20.7x (its first run in the process), repeated 12.4x; three axes at 1e5 14.9-15.4x /
6.0-6.5x; lcurve 6.4-6.6, gcv 8.3-9.1 single solves with 17 evaluations, 6.7 with 13
(4.2 and 6.7 at 1e6). On this CPU a lambda point costs about 0.4 of a single solve (a
copy of the band, ``dgbtrf`` and two ``dgbtrs``: 36 ms against 90 ms), where the eighth
session's VM measured about 0.3: the L-curve's 14 points cannot fit in five single
solves here.

Measured after the L-curve's slopes (issue 18, eighth session)
--------------------------------------------------------------
2026-12-04, main at f36f19b, the same flags (``--skip csne3@1e6,clarabel3@1e6 --memory
--huge``). The L-curve samples every two decades with exact slopes of its curvature
(7 points, the half-way points beside the best, refinement from values and slopes);
a complex-step factor's solves keep their real maps real (GCV's points 48 -> 38 ms);
the reference ran 0.039-0.060 s at 1e5 in this session's runs, so compare ratios::

    case               N  variant              time s   x ref runs     vs ref  verified
    1 ax           10000  direct                0.017     4.0    3    1.3e-12  True
    1 ax           10000  clarabel              0.052    12.4    3    2.9e-12  True   compile 0.02 s
    1 ax           10000  clarabel re-solve     0.023     5.4    3    4.8e-12  True
    1 ax           10000  osqp                 29.533  7035.2    1    1.4e-04  False  user_limit
    1 ax          100000  direct                0.097     2.1    3    1.4e-12  True
    1 ax          100000  direct backend        0.069     1.5    3    1.4e-12  -
    1 ax          100000  csne                  0.601    13.0    3    2.1e-12  True
    1 ax          100000  clarabel              0.426     9.2    3    2.2e-12  True   compile 0.12 s
    1 ax          100000  clarabel re-solve     0.224     4.9    3    1.9e-12  True
    1 ax         1000000  direct                1.174     1.9    3    3.3e-12  True
    1 ax         1000000  direct backend        0.949     1.5    3    3.3e-12  -
    1 ax         1000000  csne                  7.078    11.4    1    3.2e-12  True
    1 ax         1000000  clarabel              7.601    12.2    1    4.2e-12  True   compile 2.37 s
    1 ax         1000000  clarabel re-solve     2.707     4.4    1    2.9e-12  True
    3 ax +SF+B     10000  direct                0.052     3.6    3    2.5e-12  True
    3 ax +SF+B    100000  direct                0.394     2.6    3    2.5e-12  True
    3 ax +SF+B    100000  direct backend        0.300     1.9    3    2.5e-12  -
    3 ax +SF+B    100000  clarabel              1.723    11.3    3    2.5e-12  True   compile 0.54 s
    3 ax +SF+B    100000  clarabel re-solve     0.827     5.4    3    2.2e-12  True
    3 ax +SF+B   1000000  direct                6.596     3.1    3    3.3e-12  True
    3 ax +SF+B   1000000  direct backend        5.355     2.5    3    3.3e-12  -

    lambda rules, N = 100000, 1 axis: single direct solve 0.11 s (the reference 0.039 s)
    rule        lambda  evaluations  ms/eval  total s  x single   x ref
    lcurve    0.005152           14     31.5     0.53       4.9      14
    gcv         0.5475           17     36.5     0.68       6.3      18
    quasi        5.164           19     30.1     0.65       6.1      17

    peak resident memory, N = 1000000, 1 axis
    variant      peak MB  above base MB  B/sample  x ref
    reference        746            557       584    1.0
    direct          1108            920       965    1.7   (1.49x the reference's peak)
    csne            2108           1919      2013    3.4
    clarabel        3055           2867      3006    5.1

    --huge: direct at N = 1e7 x 1 axis: peak 9511 MB, optimal, verified, 40.2 s

The L-curve chose the same lambda (0.0051522) in 14 evaluations instead of 19; in
``lambda_table`` runs of the same hour it measured 5.0-5.7 single solves (8.0 before the
change in the same minutes: the VM ran slower then), so it sits at the target, not
safely under it. A run of the direct rows alone at c0b4d9f (``--sizes 1e5 --sizes3 1e6``)
gave 2.2x at 1e5 (0.089 s against a reference of 0.040 s) and 3.0x for three axes at
1e6: the two direct criteria move by 0.1-0.2x from run to run on this VM, around their
limits. A single solve at 1e5 spends about 25 ms planning the band (``BandPlan.build``),
19 ms in the refined solve, 8.5 ms in ``dgbtrf``, 12 ms building the least-squares
rows and about 20 ms verifying and assembling the answer; the reference has none of
the planning, verification or answer.

Measured after GCV's complex step (issue 18, seventh session)
-------------------------------------------------------------
2026-12-04, main at e723e10, the same flags (``--skip csne3@1e6,clarabel3@1e6 --memory
--huge``); this VM ran about 15 % slower than in the session below (the reference at
1e5: 0.051 s against 0.047 s), so compare the ratios. GCV's points are one complex
factorization at lambda + ih each (the real factor and two real factors at lambda
e^(+-1e-3) before); the border coupling is laid out by columns, the FEM rows written in
one CSR matrix::

    case               N  variant              time s   x ref runs     vs ref  verified
    1 ax           10000  direct                0.018     3.9    3    1.3e-12  True
    1 ax           10000  clarabel              0.054    11.8    3    2.9e-12  True   compile 0.02 s
    1 ax           10000  clarabel re-solve     0.024     5.2    3    4.8e-12  True
    1 ax          100000  direct                0.117     2.3    3    1.4e-12  True
    1 ax          100000  direct backend        0.089     1.8    3    1.4e-12  -
    1 ax          100000  csne                  0.678    13.4    3    2.1e-12  True
    1 ax          100000  clarabel              0.471     9.3    3    2.2e-12  True   compile 0.14 s
    1 ax          100000  clarabel re-solve     0.239     4.7    3    1.9e-12  True
    1 ax         1000000  direct                1.274     1.8    3    3.3e-12  True
    1 ax         1000000  direct backend        1.043     1.5    3    3.3e-12  -
    1 ax         1000000  csne                  8.323    11.9    1    3.2e-12  True
    1 ax         1000000  clarabel              8.761    12.5    1    4.2e-12  True   compile 3.17 s
    1 ax         1000000  clarabel re-solve     2.989     4.3    1    2.9e-12  True
    3 ax +SF+B    100000  direct                0.449     2.6    3    2.5e-12  True
    3 ax +SF+B    100000  direct backend        0.337     2.0    3    2.5e-12  -
    3 ax +SF+B    100000  clarabel              2.117    12.3    3    2.5e-12  True   compile 0.60 s
    3 ax +SF+B    100000  clarabel re-solve     0.930     5.4    3    2.2e-12  True
    3 ax +SF+B   1000000  direct                8.753     3.2    3    3.3e-12  True
    3 ax +SF+B   1000000  direct backend        6.307     2.5    3    3.3e-12  -

    lambda rules, N = 100000, 1 axis: single direct solve 0.11 s (the reference 0.042 s)
    rule        lambda  evaluations  ms/eval  total s  x single   x ref
    lcurve    0.005152           19     32.6     0.72       6.6      17
    gcv         0.5475           17     48.1     0.85       7.7      20
    quasi        5.164           19     32.9     0.71       6.5      17

    peak resident memory, N = 1000000, 1 axis
    variant      peak MB  above base MB  B/sample  x ref
    reference        744            556       583    1.0
    direct          1108            920       965    1.7   (1.49x the reference's peak)
    csne            2107           1919      2013    3.5
    clarabel        3055           2867      3006    5.2

    --huge: direct at N = 1e7 x 1 axis: peak 9434 MB, optimal, verified, 40.2 s

GCV went from 10.0 to 7.7 single solves (its points 45 -> 36 ms on a quiet machine, 58
-> 49 ms with the VM slower, measured in the same minutes). The L-curve and
quasi-optimality are unchanged (their points already take one real factorization and two
solves, which costs less than a complex factorization and solve): 19 evaluations of
about 30 ms, of which the LAPACK calls alone (``dgbtrf`` 8.5 ms, two ``dgbtrs`` of 4.4 ms,
the band's copy 2.6 ms) take 20 ms; with the sweep's set-up (42 ms) and the refined,
verified solve at the chosen lambda (93 ms) that is 4.7-5.2 single solves (of 0.10-0.11
s) even with every point at that floor: the target of 5 needs fewer points, not only
cheaper ones.
Three axes at 1e6: 3.2x here, 2.7-3.3x in other runs of this session; per solve about
5.6 s of user time (the reference's whole solve 2.2-2.6 s) and 3-6 s of system time
faulting in fresh memory, which moves from run to run (getrusage); the allocations of
16 MB or more fell from 10.7 to 9.7 GB per solve (memray) without a measurable change.

Measured after equal axes became one band (issue 18, sixth session)
-------------------------------------------------------------------
2026-12-04, main at c32adf9, the machine quiet, the same versions and flags as below
(``--skip csne3@1e6,clarabel3@1e6 --memory --huge``). cvxpy compiles with its SCIPY
back end (``bvpnav.backends.cvxpy_solvers.CANON_BACKEND``); axes whose band entries are
equal are assembled as one run and the border's ``A^-1 B`` is kept by axis; velocities at
given times are built from their own nodes::

    case               N  variant              time s   x ref runs     vs ref  verified
    1 ax           10000  direct                0.017     3.8    3    1.3e-12  True
    1 ax           10000  clarabel              0.056    12.2    3    2.9e-12  True   compile 0.02 s
    1 ax           10000  clarabel re-solve     0.025     5.8    3    4.8e-12  True
    1 ax           10000  osqp                 29.885  6551.0    1    1.4e-04  False  user_limit
    1 ax          100000  direct                0.107     2.3    3    1.4e-12  True
    1 ax          100000  direct backend        0.085     1.8    3    1.4e-12  -
    1 ax          100000  csne                  0.632    12.9    3    2.1e-12  True
    1 ax          100000  clarabel              0.458     9.7    3    2.2e-12  True   compile 0.14 s
    1 ax          100000  clarabel re-solve     0.228     4.8    3    1.9e-12  True
    1 ax         1000000  direct                1.185     1.7    3    3.3e-12  True
    1 ax         1000000  direct backend        0.945     1.3    3    3.3e-12  -
    1 ax         1000000  csne                  8.543    12.0    1    3.2e-12  True
    1 ax         1000000  clarabel              8.453    11.9    1    4.2e-12  True   compile 2.65 s
    1 ax         1000000  clarabel re-solve     3.526     5.0    1    2.9e-12  True
    3 ax +SF+B     10000  direct                0.053     3.7    3    2.5e-12  True
    3 ax +SF+B    100000  direct                0.411     2.5    3    2.5e-12  True
    3 ax +SF+B    100000  direct backend        0.315     1.9    3    2.5e-12  -
    3 ax +SF+B    100000  csne                  2.580    15.7    3    2.1e-12  True
    3 ax +SF+B    100000  clarabel              1.972    11.9    3    2.5e-12  True   compile 0.56 s
    3 ax +SF+B    100000  clarabel re-solve     0.889     5.5    3    2.2e-12  True
    3 ax +SF+B   1000000  direct                7.432     2.7    3    3.3e-12  True
    3 ax +SF+B   1000000  direct backend        6.506     2.4    3    3.3e-12  -

    lambda rules, N = 100000, 1 axis: single direct solve 0.10 s (the reference 0.039 s)
    rule        lambda  evaluations  total s  x single   x ref
    lcurve    0.005152           19     0.72       7.2      18
    gcv         0.5475           17     1.00      10.0      25
    quasi        5.164           19     0.68       6.8      17

    peak resident memory, N = 1000000, 1 axis
    variant      peak MB  above base MB  B/sample  x ref
    reference        745            556       583    1.0
    direct          1115            926       971    1.7   (1.50x the reference's peak)
    csne            2109           1920      2013    3.5
    clarabel        3057           2868      3007    5.2

    --huge: direct at N = 1e7 x 1 axis: peak 9434 MB, optimal, verified, 37.5 s

Clarabel's first solve at 1e6 went from 16.6-18.3x to 11.9x (cvxpy's compile 2.65 s, was
4.0-6.3 s with its default CPP back end). Three axes at 1e6 (a row this table did not
have before): 2.7x here with the reference at 2.61 s, 3.2x in a run of these rows alone
at the same commit with the reference at 2.19 s (direct 6.99 s); 4.0x before this
session's changes (a4ad84a: the dense ``A^-1 B``, its copy of ``B`` and two more axes'
band, 2 x 288 + 397 MB, were all fresh memory). This VM's cost of faulting in fresh
memory moves both: one such solve maps 6.5 GB of anonymous memory in turn (strace), and
with glibc keeping freed memory
(``GLIBC_TUNABLES=glibc.malloc.mmap_threshold=4294967295:glibc.malloc.trim_threshold=4294967295``)
it took 5.1-5.2 s against 7.9-8.4 s (before the one-band change), the reference 2.1-2.5 s
either way. A single solve got faster again, so the lambda rules' multiples did not move
(lcurve 0.72 s here, 0.70 s at a4ad84a).

Measured after the strided band writes (issue 18, fifth session)
----------------------------------------------------------------
2026-12-03, main at 0fd4261, the machine quiet, the same versions and flags as below. The
FEM diagonals are written into the band as strided slices, the verification takes the
back end's one refinement step as its forward-error estimate, the FEM rows and items are
stacked without copying the FEM block::

    case               N  variant              time s   x ref runs     vs ref  verified
    1 ax           10000  direct                0.029     4.8    3    1.3e-12  True
    1 ax           10000  clarabel              0.085    14.0    3    2.9e-12  True   compile 0.03 s
    1 ax           10000  clarabel re-solve     0.039     6.3    3    4.8e-12  True
    1 ax          100000  direct                0.166     2.5    3    1.4e-12  True
    1 ax          100000  direct backend        0.121     1.8    3    1.4e-12  -
    1 ax          100000  csne                  0.904    13.3    3    2.1e-12  True
    1 ax          100000  clarabel              0.705    10.2    3    2.2e-12  True   compile 0.25 s
    1 ax          100000  clarabel re-solve     0.323     4.7    3    1.9e-12  True
    1 ax         1000000  direct                1.730     2.0    3    3.3e-12  True
    1 ax         1000000  direct backend        1.331     1.5    3    3.3e-12  -
    1 ax         1000000  csne                 13.698    16.0    1    3.2e-12  True
    1 ax         1000000  clarabel             15.657    18.3    1    4.2e-12  True   compile 6.33 s
    1 ax         1000000  clarabel re-solve     3.933     4.6    1    2.9e-12  True
    3 ax +SF+B     10000  direct                0.096     4.4    3    4.1e-12  True
    3 ax +SF+B    100000  direct                0.720     3.0    3    2.5e-12  True
    3 ax +SF+B    100000  direct backend        0.537     2.3    3    2.5e-12  -
    3 ax +SF+B    100000  clarabel              3.282    13.8    3    2.5e-12  True   compile 1.12 s
    3 ax +SF+B    100000  clarabel re-solve     1.299     5.4    3    2.2e-12  True

    lambda rules, N = 100000, 1 axis: single direct solve 0.16 s (the reference 0.064 s)
    rule        lambda  evaluations  total s  x single   x ref
    lcurve    0.005152           19     1.18       7.4      19
    gcv         0.5475           17     1.59       9.9      25
    quasi        5.164           19     1.17       7.3      18

    peak resident memory, N = 1000000, 1 axis
    variant      peak MB  above base MB  B/sample  x ref
    reference        744            549       576    1.0
    direct          1114            919       964    1.7   (1.50x the reference's peak)
    csne            2107           1913      2006    3.5
    clarabel        3055           2860      2999    5.2

    --huge: direct at N = 1e7 x 1 axis: peak 9423 MB, optimal, verified, 63.2 s

Absolute times on this VM drift by 20-40 % between hours (the reference took 0.051 s at
1e5 in the fourth session's run, 0.064-0.078 s in this one; first touches of fresh memory
cost up to 2 ms/MB), so only ratios from one run compare. The lambda rules cost as many
seconds as in the fourth session's code on the same hour (lcurve 1.27 s at c79fb1f, 1.33 s
at d0c8335, 1.18 s here): their multiples grew because the single solve they are divided
by got faster. Clarabel's first solve at 1e6 is cvxpy's compile (6.3 s here, 4.4 s in the
fourth session) plus the solve; it is the noisiest row.

Between the fourth session's run and this one: ``direct`` 3.3x/2.6x -> 2.5x/2.0x (N =
1e5/1e6), three axes 3.9x -> 3.0x, the back end alone 2.3x/2.0x -> 1.8x/1.5x, its peak at
1e6 1.20 -> 1.11 GB. In the fourth session (assembly by diagonals, 2026-12-03): ``direct``
3.3x/2.6x, three axes 3.9x, lcurve/gcv/quasi 5.0/7.1/4.9 single solves of 0.19 s,
Clarabel 11x/14x first solve and 5.1x/4.4x re-solve, peak 1.20 GB at 1e6, 10.2 GB at 1e7.
Earlier (issue 18, 2026-12-02 and 03; the tables are in the git history of this file): the
banded direct path took ``direct`` from 6.4x/4.9x the reference to 4.0x/3.8x and three
axes from 10.5x to 5.6x, and its peak at 1e6 from 2.17 to 1.39 GB; the lambda sweep on the
band affine in lambda took lcurve/gcv/quasi from 35/84/41 single solves to 8.2/14.8/7.5,
then the seeded parabolic refinement to 4.7/6.3/4.7 (with a single solve of 0.23 s); kl = 4
and the band plan's caches took ``direct`` to 4.0x/3.2x and 1.25 GB; clarabel 0.11.1 with
cvxpy 1.9.3 took Clarabel's first solve to 12x/17x and its re-solve to 6.0x/5.3x.

Measured on main before the structured path
--------------------------------------------
2026-12-02, main at ce989e5 (this branch adds only the benchmark), a 2-core VM shared with
three other jobs (load average about 2.5-3.5: absolute times are noisy, the interleaved
ratios are what count), BLAS on one thread. 1e4/1e5 rows and the lambda and peers tables
from ``--sizes 1e4,1e5``; 1e6 rows from ``--sizes 1e6 --skip csne3@1e6,clarabel3@1e6``
(csne did not finish in 330 s there in issue 18; Clarabel would need ~15 GB); memory from
``--memory``. ``vs ref``: max|r - r_ref| / max|r_ref|::

    case               N  variant              time s   x ref runs     vs ref  verified note
    1 ax           10000  reference             0.014     1.0    3    0.0e+00  -
    1 ax           10000  direct                0.081     5.5    3    2.1e-12  True     ldl, 3 refinements
    1 ax           10000  direct backend        0.047     3.2    3    2.1e-12  -
    1 ax           10000  csne                  0.228    16.1    3    1.6e-12  True     inaccurate, 20 it.
    1 ax           10000  clarabel              0.274    19.8    3    7.2e-11  True     compile 0.06 s
    1 ax           10000  clarabel re-solve     0.139    10.1    3    3.7e-11  True     lam=2, optimal
    1 ax           10000  osqp                104.220  7358.9    1    1.4e-04  False    user_limit
    1 ax          100000  reference             0.125     1.0    3    0.0e+00  -
    1 ax          100000  direct                0.794     6.4    3    2.8e-12  True     ldl, 3 refinements
    1 ax          100000  direct backend        0.578     4.6    3    2.8e-12  -
    1 ax          100000  csne                  2.190    17.1    3    2.1e-12  True     inaccurate, 20 it.
    1 ax          100000  clarabel              3.741    30.5    3    2.6e-11  True     compile 0.61 s
    1 ax          100000  clarabel re-solve     1.239     9.9    3    1.4e-11  True     lam=2, optimal
    1 ax         1000000  reference             1.207     1.0    3    0.0e+00  -
    1 ax         1000000  direct                5.729     4.9    3    2.9e-12  True     ldl, 3 refinements
    1 ax         1000000  direct backend        4.561     3.8    3    2.9e-12  -
    1 ax         1000000  csne                 12.049    10.0    1    3.2e-12  True     inaccurate, 20 it.
    1 ax         1000000  clarabel             22.151    18.4    1    2.6e-11  True     compile 8.53 s
    1 ax         1000000  clarabel re-solve     9.788     8.1    1    2.0e-11  True     lam=2, optimal
    3 ax +SF+B     10000  reference             0.033     1.0    3    0.0e+00  -
    3 ax +SF+B     10000  direct                0.302     9.2    3    2.6e-12  True     ldl, 3 refinements
    3 ax +SF+B     10000  direct backend        0.216     6.5    3    2.6e-12  -
    3 ax +SF+B     10000  csne                  0.804    23.9    3    3.3e-12  True     inaccurate, 20 it.
    3 ax +SF+B     10000  clarabel              0.853    25.4    3    6.3e-11  True     compile 0.14 s
    3 ax +SF+B     10000  clarabel re-solve     0.368    12.4    3    4.2e-11  True     lam=2, optimal
    3 ax +SF+B    100000  reference             0.323     1.0    3    0.0e+00  -
    3 ax +SF+B    100000  direct                3.989    10.5    3    2.2e-12  True     ldl, 3 refinements
    3 ax +SF+B    100000  direct backend        2.833     8.8    3    2.2e-12  -
    3 ax +SF+B    100000  csne                  6.892    21.8    3    2.1e-12  True     inaccurate, 20 it.
    3 ax +SF+B    100000  clarabel              7.468    37.8    3    2.1e-11  True     compile 1.18 s
    3 ax +SF+B    100000  clarabel re-solve     4.049    20.4    3    1.7e-11  True     lam=2, optimal
    3 ax +SF+B   1000000  reference             3.730     1.0    3    0.0e+00  -
    3 ax +SF+B   1000000  direct               32.195     9.1    3    3.2e-12  True     ldl, 3 refinements
    3 ax +SF+B   1000000  direct backend       26.346     8.0    3    3.2e-12  -

    lambda rules, N = 100000, 1 axis: single direct solve 0.66 s (the reference 0.081 s)
    rule        lambda  evaluations  total s  x single   x ref
    lcurve    0.005153           33    22.96      35.0     284
    gcv         0.6387           34    55.21      84.1     682
    quasi        5.164           32    26.64      40.6     329

    lambda rules, N = 1000000, 1 axis (--lam-n 1e6): single direct solve 12.55 s (the
    first 1e6 solve of that process; 5.7 s in the speed table), the reference 1.156 s
    rule        lambda  evaluations  total s  x single   x ref
    lcurve     0.01145           33   292.74      23.3     253
    gcv         0.7651           34   505.78      40.3     438
    quasi        3.234           33   366.78      29.2     317

    peak resident memory, N = 1000000, 1 axis (one child process each; VmHWM)
    variant      peak MB  above base MB  B/sample  x ref  time s  note
    baseline         195                                          imports + data + problem with its items
    reference        745            550       577    1.0    1.24
    direct          2170           1975      2071    3.6    6.07  optimal, verified=True
    csne            2795           2600      2726    4.7   16.19  inaccurate, verified=True
    clarabel        5531           5336      5595    9.7   22.96  optimal, verified=True

    peers (1 axis, orientation only)   N   time s   x ref    vs ref
    rts_smoother                   10000     0.72      78   5.5e-05
    filterpy                       10000     0.47      51   5.5e-05
    pykalman                       10000     1.33     143   5.5e-05
    rts_smoother                  100000     5.27      41   5.3e-06
    filterpy                      100000     2.28      18   5.3e-06
    pykalman                      100000     5.34      42   5.3e-06

``--huge`` (the machine's other jobs left 7-10 GB available, so the runs were capped):
``--huge-n 2e6 --huge-cap 5.5``: baseline 256 MB, ``direct`` peak 4119 MB (2025 B/sample
above the baseline, linear with the 1e6 row), verified, 33 s; ``--huge-cap 6`` at 1e7:
bvpnav itself refuses (``InputError``: needs about 19.5 GB by its 1950 B/sample estimate,
6.6 GB available); by the measured slope 1e7 needs about 20.3 GB above a 0.7 GB baseline,
at the edge of a 24 GB machine.
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # a script (or a memory child): one BLAS thread from the start
    for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from collections.abc import Callable  # noqa: E402
from contextlib import nullcontext  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _banded_reference import Spec, reference_solve  # noqa: E402
from _memory import own_peak_mb, run_case  # noqa: E402

import bvpnav  # noqa: E402
from bvpnav.backends import resolve_solver, solver_options  # noqa: E402
from bvpnav.constraints import Position, Velocity  # noqa: E402
from bvpnav.error_models import Bias, ScaleFactor  # noqa: E402

#: Largest N at which OSQP runs (--osqp-max; at 1e4 it stops at its iteration limit after ~65 s).
OSQP_MAX = 10_000
SCALE = np.array([0.01, -0.02, 0.005])
BIAS = np.array([0.05, -0.03, 0.02])


def one_thread():
    """A context limiting BLAS/OpenMP pools to one thread (threadpoolctl), else a no-op."""
    if importlib.util.find_spec("threadpoolctl") is None:
        return nullcontext()
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1)


# ------------------------------------------------------------------ problems
def make_spec(n: int, axes: int = 1, error_model: bool = False, seed: int = 0) -> Spec:
    """The benchmark problem in plain arrays (see the module docstring).

    Parameters
    ----------
    n : int
        Samples (100 Hz).
    axes : int
        1 to 3.
    error_model : bool
        Scale factor and bias errors in the measurements and ``ScaleFactor() + Bias()``.
    seed : int
    """
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.01
    amp, om, ph = np.array([0.5, 0.3, 0.2])[:axes], np.array([0.3, 0.5, 0.7])[:axes], np.arange(axes)
    acc = amp * np.sin(om * t[:, None] + ph)
    truth = -amp / om**2 * np.sin(om * t[:, None] + ph) + 2.0 * t[:, None]
    if error_model:
        acc = (1.0 + SCALE[:axes]) * acc + BIAS[:axes]
    acc += 0.05 * rng.normal(size=(n, axes))
    T = float(t[-1])
    pos_t = np.arange(0.505, T, 1.0)
    j = np.searchsorted(t, pos_t) - 1
    th = ((pos_t - t[j]) / (t[j + 1] - t[j]))[:, None]
    pos_val = (1 - th) * truth[j] + th * truth[j + 1] + rng.normal(size=(pos_t.size, axes))
    ends = np.array([0.0, T])
    vel_val = -amp / om * np.cos(om * ends[:, None] + ph) + 2.0 + 0.05 * rng.normal(size=(2, axes))
    return Spec(t, acc, 0.05, pos_t, pos_val, 1.0, ends, truth[[0, -1]], vel_val, 0.05, error_model, truth)


def make_problem(spec: Spec) -> bvpnav.NavigationProblem:
    """The same problem as a :class:`bvpnav.NavigationProblem` (items not compiled)."""
    one = spec.d == 1

    def v(x: np.ndarray) -> np.ndarray:
        return x[:, 0] if one else x

    data = bvpnav.ImuData(spec.t, v(spec.acc))
    em = ScaleFactor() + Bias() if spec.error_model else None
    prob = bvpnav.NavigationProblem(data, sigma_a=spec.sigma_a, error_model=em)
    prob.add(Position(t=spec.hard_t, value=v(spec.hard_val), name="ends"))
    prob.add(Position(t=spec.pos_t, value=v(spec.pos_val), sigma=spec.pos_sigma, name="gnss"))
    prob.add(Velocity(t=spec.hard_t, value=v(spec.vel_val), sigma=spec.vel_sigma, name="end velocities"))
    return prob


def trajectory(prob: bvpnav.NavigationProblem, x: np.ndarray) -> np.ndarray:
    """Nodal positions (N, d) from bvpnav's stacked unknowns."""
    m = prob.formulation.model
    return np.column_stack([x[m.r_index(a)] for a in range(m.d)])


def rel_diff(r: np.ndarray, ref: np.ndarray) -> float:
    """``max|r - ref| / max|ref|``."""
    return float(np.max(np.abs(r - ref)) / np.max(np.abs(ref)))


# ------------------------------------------------------------------ variants
def _quiet(f: Callable):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return f()


def run_variant(name: str, spec: Spec, state: dict) -> dict:
    """One timed run of a variant; returns ``time``, ``r`` and notes.

    ``state`` carries the clarabel problem from its first solve to the re-solve.
    """
    if name == "reference":
        t0 = time.perf_counter()
        r = reference_solve(spec, 1.0)
        return {"time": time.perf_counter() - t0, "r": r, "verified": None}
    if name == "direct backend":
        prob = make_problem(spec)
        t0 = time.perf_counter()
        prob.terms()
        tc = time.perf_counter() - t0
        be = resolve_solver("direct")
        t0 = time.perf_counter()
        raw = be.run(prob.formulation, 1.0, solver_options(be, "default"))
        return {"time": time.perf_counter() - t0, "r": trajectory(prob, raw.x), "verified": None,
                "note": f"items compiled before: {tc:.2f} s"}
    if name == "clarabel re-solve":
        prob = state.pop("clarabel")
        t0 = time.perf_counter()
        sol = _quiet(lambda: prob.solve(solver="clarabel", lam=2.0, fallback=None, verify=True))
        dt = time.perf_counter() - t0
        ref2 = state.setdefault("ref_lam2", reference_solve(spec, 2.0))
        return {"time": dt, "r": trajectory(prob, sol.x), "verified": sol.stats["verified"],
                "ref": ref2, "note": f"lam=2, {sol.stats['status']}"}
    prob = make_problem(spec)
    solver = name.split()[0]
    verify = solver != "osqp"
    t0 = time.perf_counter()
    try:
        sol = _quiet(lambda: prob.solve(solver=solver, fallback=None, verify=verify))
    except bvpnav.BvpnavError as exc:
        return {"time": time.perf_counter() - t0, "r": None, "verified": False,
                "note": f"{type(exc).__name__}: {str(exc)[:60]}"}
    dt = time.perf_counter() - t0
    note = f"{sol.stats['status']}"
    if solver == "clarabel":
        state["clarabel"] = prob
        note += f", compile {sol.stats.get('compile_time', float('nan')):.2f} s"
    if solver == "direct":
        note += f", {sol.stats['factorization']}, {sol.stats['refinements']} refinements"
    if solver == "csne":
        note += f", {sol.stats['iterations']} iterations"
    ver = sol.stats["verified"] if verify else sol.stats.get("verified")
    return {"time": dt, "r": trajectory(prob, sol.x), "verified": ver, "note": note}


#: Variants repeated at N >= 1e6 too (the others run once there, see ``speed_case``): the
#: acceptance rows (issue 18).
REPEATED = ("reference", "direct", "direct backend", "clarabel", "clarabel re-solve")
VARIANTS = ("reference", "direct", "direct backend", "csne", "clarabel", "clarabel re-solve", "osqp")


def wanted(name: str, axes: int, n: int, skip: set[str]) -> bool:
    """Whether variant ``name`` runs for this case (``--skip`` and the built-in limits)."""
    suffix = "3" if axes > 1 else ""
    names = {name.split()[0] + suffix, name.replace(" ", "-") + suffix}
    for tag in skip:
        what, _, size = tag.partition("@")
        if what in names and (not size or int(float(size)) == n):
            return False
    if name == "osqp":
        return n <= OSQP_MAX and axes == 1
    return True


def speed_case(n: int, axes: int, repeat: int, skip: set[str]) -> list[dict]:
    """Interleaved timings of every variant for one case; median of the per-repetition ratios."""
    spec = make_spec(n, axes, error_model=axes > 1)
    names = [v for v in VARIANTS if wanted(v, axes, n, skip)]
    if "clarabel" not in names and "clarabel re-solve" in names:
        names.remove("clarabel re-solve")
    runs: dict[str, list[dict]] = {v: [] for v in names}
    for k in range(repeat):
        state: dict = {}
        for v in names:
            if k > 0 and (v == "osqp" or (n >= 1_000_000 and v not in REPEATED)):
                continue
            rec = run_variant(v, spec, state)
            rec["rep"] = k
            runs[v].append(rec)
    ref = runs["reference"][-1]["r"]
    t_ref = [rr["time"] for rr in runs["reference"]]
    rows = []
    for v in names:
        rs = runs[v]
        # per-repetition ratios; a variant run once against the median of the reference's runs
        ratios = ([rr["time"] / t_ref[rr["rep"]] for rr in rs] if len(rs) > 1 or repeat == 1
                  else [rs[0]["time"] / float(np.median(t_ref))])
        last = rs[-1]
        note = last.get("note", "")
        if v.startswith("clarabel") and len(rs) > 1:
            note += f", first run {rs[0]['time']:.2f} s"
        err = rel_diff(last["r"], last.get("ref", ref)) if last["r"] is not None else float("nan")
        rows.append({"case": f"{axes} ax" + (" +SF+B" if axes > 1 else ""), "n": n, "variant": v,
                     "time": float(np.median([rr["time"] for rr in rs])), "ratio": float(np.median(ratios)),
                     "runs": len(rs), "agree": err, "verified": last["verified"],
                     "note": note})
        del rs
    return rows


def print_speed(rows: list[dict]) -> None:
    """The speed table."""
    for r in rows:
        ver = "-" if r["verified"] is None else str(bool(r["verified"]))
        print(f"{r['case']:<11}{r['n']:>9}  {r['variant']:<18}{r['time']:>9.3f}{r['ratio']:>8.1f}"
              f"{r['runs']:>5}{r['agree']:>11.1e}  {ver:<9}{r['note']}", flush=True)


SPEED_HEAD = (f"{'case':<11}{'N':>9}  {'variant':<18}{'time s':>9}{'x ref':>8}{'runs':>5}{'vs ref':>11}  "
              f"{'verified':<9}note")


# ------------------------------------------------------------------ lambda rules
def lambda_table(n: int, repeat: int = 3) -> None:
    """The lambda rules as multiples of a single direct solve (1 axis), each rule's run
    beside a single solve (the median of ``repeat`` per-run ratios, as in the speed table: the
    VM's speed drifts over a run)."""
    spec = make_spec(n, 1)
    _quiet(lambda: make_problem(spec).solve(solver="direct"))   # warm-up (first-call imports)

    def timed_solve(lam=None):
        prob = make_problem(spec)
        t0 = time.perf_counter()
        sol = _quiet(lambda: prob.solve(solver="direct") if lam is None else
                     prob.solve(solver="direct", lam=lam))
        return time.perf_counter() - t0, sol

    singles, rows = [], []
    for rule in ("lcurve", "gcv", "quasi"):
        ratios, times = [], []
        for _ in range(repeat):   # (a rule's first run pays its own warm-up: the median drops it)
            single = timed_solve()[0]
            dt, sol = timed_solve(rule)
            singles.append(single)
            ratios.append(dt / single)
            times.append(dt)
        rows.append((rule, sol, float(np.median(times)), float(np.median(ratios))))
    t_ref = min(_timed(lambda: reference_solve(spec)) for _ in range(2))
    print(f"\nlambda rules, N = {n}, 1 axis: single direct solve {float(np.median(singles)):.2f} s "
          f"(the reference {t_ref:.3f} s; x single: the median of {repeat} ratios to a solve beside it)")
    print(f"{'rule':<8}{'lambda':>10}{'evaluations':>13}{'ms/eval':>9}{'total s':>9}{'x single':>10}"
          f"{'x ref':>8}  warnings")
    for rule, sol, dt, ratio in rows:
        curve = sol.curve
        warn = "; ".join(w[:70] for w in getattr(curve, "warnings", [])) or "-"
        per = 1e3 * curve.seconds / max(curve.evaluations, 1)   # the sweep's time per lambda
        print(f"{rule:<8}{sol.lam:>10.4g}{curve.evaluations:>13d}{per:>9.1f}{dt:>9.2f}{ratio:>10.1f}"
              f"{dt / t_ref:>8.0f}  {warn}", flush=True)


def _timed(f: Callable) -> float:
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


# ------------------------------------------------------------------ memory
def child(n: int, axes: int, what: str) -> dict:
    """One memory case (run in a child process): build, solve once, report the peak."""
    spec = make_spec(n, axes, error_model=axes > 1)
    prob = make_problem(spec)
    t0 = time.perf_counter()
    out: dict = {"n": n, "what": what}
    if what == "reference":
        reference_solve(spec)
    elif what != "baseline":
        sol = _quiet(lambda: prob.solve(solver=what, fallback=None, verify=False))
        out.update(status=sol.stats["status"], verified=bool(sol.stats["verified"]))
    out.update(time=time.perf_counter() - t0, peak_mb=own_peak_mb())
    return out


def memory_table(n: int) -> None:
    """Peak memory per variant at ``n`` (1 axis), each in its own process."""
    print(f"\npeak resident memory, N = {n}, 1 axis (one child process each; VmHWM)")
    print(f"{'variant':<11}{'peak MB':>9}{'above base MB':>15}{'B/sample':>10}{'x ref':>7}"
          f"{'time s':>8}  note")
    base = run_case(__file__, [str(n), "1", "baseline"])
    rows = [(w, run_case(__file__, [str(n), "1", w])) for w in ("reference", "direct", "csne", "clarabel")]
    print(f"{'baseline':<11}{base['peak_mb']:>9.0f}{'':>15}{'':>10}{'':>7}{base.get('time', 0):>8.2f}  "
          "imports + data + problem with its items", flush=True)
    ref_above = rows[0][1]["peak_mb"] - base["peak_mb"]
    for w, r in rows:
        above = r["peak_mb"] - base["peak_mb"]
        note = r.get("error") or (f"{r['status']}, verified={r['verified']}" if "status" in r else "")
        print(f"{w:<11}{r['peak_mb']:>9.0f}{above:>15.0f}{above * 2**20 / n:>10.0f}{above / ref_above:>7.1f}"
              f"{r.get('time', float('nan')):>8.2f}  {note}", flush=True)


def huge(n: int, cap_gb: float) -> None:
    """``direct`` at ``n`` x 1 axis in a child capped at ``cap_gb`` GB of address space."""
    print(f"\n--huge: direct at N = {n:.0e} x 1 axis, child capped at {cap_gb:g} GB (RLIMIT_AS)")
    base = run_case(__file__, [str(n), "1", "baseline", str(cap_gb)])
    r = run_case(__file__, [str(n), "1", "direct", str(cap_gb)])
    print(f"baseline {base['peak_mb']:.0f} MB; direct: peak {r['peak_mb']:.0f} MB, "
          f"{r.get('error') or (str(r.get('status')) + ', verified=' + str(r.get('verified')))}"
          f", {r.get('time', float('nan')):.1f} s", flush=True)


# ------------------------------------------------------------------ peers
def peers_table(ns: list[int]) -> None:
    """Kalman/RTS smoothers on the 1-axis measurements (different model; orientation only)."""
    from bvpnav.baselines import rts_smoother

    print("\npeers (1 axis; Kalman filter + RTS smoother, state position/velocity; per-sample white "
          "acceleration noise: a different model, for orientation)")
    print(f"{'peer':<14}{'N':>9}{'time s':>9}{'x ref':>8}{'vs ref':>10}  note")
    have_fp = importlib.util.find_spec("filterpy") is not None
    have_pk = importlib.util.find_spec("pykalman") is not None
    for n in ns:
        spec = make_spec(n, 1)
        t_ref = min(_timed(lambda spec=spec: reference_solve(spec)) for _ in range(2))
        ref = reference_solve(spec)
        meas = _measurements(spec)
        t0 = time.perf_counter()
        df = rts_smoother(spec.t, spec.acc[:, 0], meas, sigma_a=spec.sigma_a, bias0_std=0.0)
        dt = time.perf_counter() - t0
        _peer_row("rts_smoother", n, dt, t_ref, df["position"].to_numpy(), ref, "bvpnav.baselines")
        peers = (("filterpy", have_fp, _filterpy, "its KalmanFilter forward, the RTS pass by hand (input u)"),
                 ("pykalman", have_pk, _pykalman, "KalmanFilter.smooth; missing component: variance 1e12"))
        for name, have, f, note in peers:
            if not have:
                print(f"{name:<14}{n:>9}  not installed (pip install bvpnav[peers])")
                continue
            if name == "pykalman" and n > 100_000:
                print(f"{name:<14}{n:>9}  skipped above N = 1e5")
                continue
            t0 = time.perf_counter()
            r = f(spec)
            dt = time.perf_counter() - t0
            _peer_row(name, n, dt, t_ref, r, ref, note)


def _peer_row(name: str, n: int, dt: float, t_ref: float, r: np.ndarray, ref: np.ndarray, note: str) -> None:
    print(f"{name:<14}{n:>9}{dt:>9.2f}{dt / t_ref:>8.0f}{rel_diff(r, ref[:, 0]):>10.1e}  {note}", flush=True)


def _measurements(spec: Spec) -> list:
    """Per-sample measurements for the smoothers: positions moved to the nearest sample."""
    k = np.clip(np.round(spec.pos_t / 0.01).astype(int), 0, spec.n - 1)
    out = [(spec.t[i], "position", float(v), spec.pos_sigma)
           for i, v in zip(k, spec.pos_val[:, 0], strict=True)]
    for i, j in enumerate((0, spec.n - 1)):
        out.append((spec.t[j], "position", float(spec.hard_val[i, 0]), 1e-6))
        out.append((spec.t[j], "velocity", float(spec.vel_val[i, 0]), spec.vel_sigma))
    return out


def _kalman_arrays(spec: Spec):
    """Transition, process noise and the per-sample measurements (NaN where none) for the peers."""
    h = 0.01
    F = np.array([[1.0, h], [0.0, 1.0]])
    g = np.array([0.5 * h * h, h])
    Q = spec.sigma_a**2 * np.outer(g, g) + 1e-12 * np.eye(2)
    z = np.full((spec.n, 2), np.nan)
    R = np.full((spec.n, 2), np.inf)
    for tm, kind, val, std in _measurements(spec):
        j = int(round(tm / h))
        c = 0 if kind == "position" else 1
        z[j, c], R[j, c] = val, std**2
    u = np.empty(spec.n)
    u[:-1] = 0.5 * (spec.acc[:-1, 0] + spec.acc[1:, 0])
    u[-1] = spec.acc[-1, 0]
    return F, g, Q, z, R, u


def _filterpy(spec: Spec) -> np.ndarray:
    from filterpy.kalman import KalmanFilter

    F, g, Q, z, R, u = _kalman_arrays(spec)
    kf = KalmanFilter(dim_x=2, dim_z=1, dim_u=1)
    kf.F, kf.B, kf.Q = F, g[:, None], Q
    kf.P = np.diag([1e6, 1e6])
    n = spec.n
    xs, Ps, Fs, Qs = np.empty((n, 2)), np.empty((n, 2, 2)), np.empty((n, 2, 2)), np.empty((n, 2, 2))
    for k in range(n):
        if k:
            kf.predict(u=np.array([[u[k - 1]]]))
        for c in (0, 1):
            if np.isfinite(z[k, c]):
                H = np.zeros((1, 2))
                H[0, c] = 1.0
                kf.update(np.array([z[k, c]]), R=np.array([[R[k, c]]]), H=H)
        xs[k], Ps[k], Fs[k], Qs[k] = kf.x.ravel(), kf.P, F, Q
    # the smoother ignores the control input: add it back through the predicted means
    xs_s = xs.copy()
    P_s = Ps.copy()
    for k in range(n - 2, -1, -1):
        Pp = F @ Ps[k] @ F.T + Q
        C = np.linalg.solve(Pp, F @ Ps[k]).T
        xs_s[k] = xs[k] + C @ (xs_s[k + 1] - (F @ xs[k] + g * u[k]))
        P_s[k] = Ps[k] + C @ (P_s[k + 1] - Pp) @ C.T
    return xs_s[:, 0]


def _pykalman(spec: Spec) -> np.ndarray:
    from pykalman import KalmanFilter

    F, g, Q, z, R, u = _kalman_arrays(spec)
    # pykalman skips an observation with any masked component: a missing component of a
    # partly observed sample gets the value 0 with variance 1e12 instead (time-varying R)
    none = ~np.isfinite(z).any(axis=1)
    zz = np.where(np.isfinite(z), z, 0.0)
    Rk = np.where(np.isfinite(R), R, 1e12)
    obs = np.ma.array(zz, mask=np.repeat(none[:, None], 2, axis=1))
    kf = KalmanFilter(transition_matrices=F, observation_matrices=np.eye(2),
                      transition_covariance=Q, observation_covariance=np.stack([np.diag(r) for r in Rk]),
                      transition_offsets=(g[None, :] * u[:-1, None]),
                      initial_state_mean=np.zeros(2), initial_state_covariance=np.diag([1e6, 1e6]),
                      n_dim_state=2, n_dim_obs=2)
    means, _ = kf.smooth(obs)
    return means[:, 0]


# ------------------------------------------------------------------ profile
def profile(n: int, axes: int, top: int = 30) -> None:
    """cProfile of one ``prob.solve(solver="direct")`` (the problem built beforehand)."""
    import cProfile
    import pstats

    _quiet(lambda: make_problem(make_spec(2000, axes, error_model=axes > 1)).solve(solver="direct"))
    spec = make_spec(n, axes, error_model=axes > 1)
    prob = make_problem(spec)
    pr = cProfile.Profile()
    t0 = time.perf_counter()
    pr.enable()
    _quiet(lambda: prob.solve(solver="direct"))
    pr.disable()
    print(f"\ncProfile of direct, N = {n}, {axes} axis/axes: {time.perf_counter() - t0:.2f} s "
          f"(the reference: {_timed(lambda: reference_solve(spec)):.2f} s)")
    pstats.Stats(pr).sort_stats("cumulative").print_stats(top)
    pstats.Stats(pr).sort_stats("tottime").print_stats(top // 2)


# ------------------------------------------------------------------ main
def main(argv: list[str] | None = None) -> None:
    """Command line (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N = 2e3, 1e4 (seconds)")
    ap.add_argument("--sizes", default="1e4,1e5,1e6", help="1-axis sizes")
    ap.add_argument("--sizes3", default=None, help="3-axis sizes (default: --sizes)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip", default="", help="variants to leave out, e.g. csne3@1e6,clarabel3@1e6")
    ap.add_argument("--lam-n", type=float, default=1e5)
    ap.add_argument("--lam-huge", action="store_true", help="also the lambda rules at N = 1e6")
    ap.add_argument("--no-lam", action="store_true")
    ap.add_argument("--memory", action="store_true", help="peak memory per variant, child processes")
    ap.add_argument("--memory-n", type=float, default=1e6)
    ap.add_argument("--no-peers", action="store_true")
    ap.add_argument("--huge", action="store_true", help="direct at 1e7 x 1 axis in a capped child")
    ap.add_argument("--huge-cap", type=float, default=16.0, help="GB of address space for --huge")
    ap.add_argument("--huge-n", type=float, default=1e7, help="N for --huge (default 1e7)")
    ap.add_argument("--osqp-max", type=float, default=1e4, help="largest N for OSQP (1 axis, one run)")
    ap.add_argument("--profile", type=float, default=None, metavar="N",
                    help="only: cProfile of one direct solve at N (1 axis; --profile-axes 3)")
    ap.add_argument("--profile-axes", type=int, default=1)
    ap.add_argument("--case", nargs="+", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.case:  # a memory child: N AXES WHAT [CAP_GB]
        if len(args.case) > 3:
            import resource

            cap = int(float(args.case[3]) * 2**30)
            resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
        with one_thread():
            print(json.dumps(child(int(float(args.case[0])), int(args.case[1]), args.case[2])))
        return
    if args.profile:
        with one_thread():
            profile(int(args.profile), args.profile_axes)
        return
    if args.quick:
        sizes, sizes3, lam_n, mem_n = [2000, 10000], [2000, 10000], 10000, 20000
    else:
        sizes = [int(float(s)) for s in args.sizes.split(",") if s]
        sizes3 = [int(float(s)) for s in (args.sizes if args.sizes3 is None else args.sizes3).split(",") if s]
        lam_n, mem_n = int(args.lam_n), int(args.memory_n)
    global OSQP_MAX
    OSQP_MAX = 2000 if args.quick else int(args.osqp_max)
    skip = {s.strip() for s in args.skip.split(",") if s.strip()}
    with one_thread():
        reference_solve(make_spec(2000, 3, True))  # warm up imports and first calls
        _quiet(lambda: make_problem(make_spec(2000, 1)).solve(solver="direct"))
        print("speed: ratios to the reference measured in the same process, interleaved, median of "
              f"{args.repeat} (at N >= 1e6 csne runs once and is divided by the median of the "
              "reference's runs; Clarabel's notes give the first run's time too); "
              "vs ref = max|r - r_ref| / max|r_ref|")
        print(SPEED_HEAD)
        for axes, ns in ((1, sizes), (3, sizes3)):
            for n in ns:
                print_speed(speed_case(n, axes, args.repeat, skip))
        if not args.no_lam:
            lambda_table(lam_n, args.repeat)
            if args.lam_huge:
                lambda_table(1_000_000, args.repeat)
        if not args.no_peers:
            peers_table([n for n in sizes if n <= 100_000])
    if args.memory:
        memory_table(mem_n)
    if args.huge:
        huge(int(args.huge_n), args.huge_cap)


if __name__ == "__main__":
    main()
