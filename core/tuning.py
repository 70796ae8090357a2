"""Every tuned constant of the library, with why the value and what was measured.

Numbers that are conventions or definitions (the paper's k = 15, eq. 14's kernel,
the 1.345 / 4.685 efficiency constants of Huber and Tukey) are tuning too where a user
could reasonably want another value; structural sizes (how many monomials a cubic has)
live with the code that needs them. The compiled kernels take these values as
arguments, so a change here is seen without clearing numba's cache.
"""

from __future__ import annotations

# ----------------------------------------------------------------------------- linear algebra

#: singularity threshold of an equilibrated (unit-diagonal) normal matrix: its smallest
#: eigenvalue relative to the largest (numpy fits), its determinant (the 3x3 closed form)
#: or its Cholesky pivots (compiled fits). 1e-10 rejects collinear or duplicated
#: neighbourhoods while keeping thin but honest ones (measured: no valid point of the
#: torus, saddle or cube is lost at k = 15).
RCOND = 1e-10
#: the same threshold for the position jets of k="auto" (core.scale.choose_jets, their cubic and quartic fits). On an
#: exact grid whose spacing differs between its two directions (a UV sphere's vertices, a parametric torus, gridded
#: terrain) the k nearest can lie on three grid lines, where a cubic is not determined (u^3 is a combination of 1, u,
#: u^2 on three values of u); rounding and the surface's bend leave pivots of 1e-15 to 1e-6 there, which RCOND passed:
#: normals 25-76 degrees off, valid. Honest samplings (uniform random, hex, square grid; 300 centres each, torus and
#: chirp, 15-56 neighbours): cubic pivots >= 6e-4, quartic >= 1e-5. The hold-out race is unchanged cell for cell.
#: 1e-6 -> 1e-5 (2026-12-05): on an exact grid 5x sparser across its rows, turned 22.5 degrees and rotated in space, two
#: cubic jets on 40 neighbours passed 1e-6 with |H| errors of 8 and 13 (normals right); at 1e-5 the turned cloud's
#: errors equal the unturned one's (mean 5.3e-4, largest 0.03). Both races unchanged.
JET_RCOND = 1e-5
#: a normal fit of degree 2 or 3 (k="auto"'s cubic normal field, or options={"degree": ...}) falls a degree where the
#: smallest eigenvalue of its normal matrix, the monomials scaled per degree so that no turn of the tangent axes changes
#: it (core.kernels.algebra.determined), is at most this: on two to four scan lines the terms across them fit the lines'
#: own bend. Measured (200-400 centres): uniform torus, 1st percentile 1.6e-4, 2.9e-3, 8.9e-3 at 15, 20, 28 neighbours
#: (13 %, 0, 0 fall); sphere parallels 6-16 spacings apart, median 1e-6 to 3e-4 at 28-56 (all fall). Until 2026-12-07
#: the smallest equilibrated Cholesky pivot in world-fixed axes (1e-2): a turned cloud fell at other points (H off by
#: 0.09 where |H| <= 0.1) and 21-64 % of those parallels' fits passed. Parallels 6-16 apart (k="auto"), mean ||H| - 1|:
#: noise-free 0.0008-0.0036 -> 0.0004-0.0034, noise 0.1 0.037-0.086 -> 0.006-0.026. Races: tuning 1/72 0.471x, private
#: 1/48 1.20x 0.419x, hold-out 3/84 1.35x 0.447x (were 1.21x, 1.33x 0.445x).
DEGREE_PIVOT = 2e-3
#: the same for the initial 2-jet normal of k="auto" (core.normals.jet_normals): at most this and the
#: quadratic is not determined and the point keeps its PCA normal. On an exact grid 5x sparser across
#: its rows an undetermined 2-jet is wrong (454 initial normals 10-63 degrees off with no test): 15 %
#: of its 15-neighbour rows there are below 3e-5 (9 % below 1e-5), uniform rows above 1e-2. Before
#: 2026-12-07 the smallest equilibrated pivot in world-fixed axes (1e-4), measured then: better than
#: 1e-2 on noisy parallels 6 spacings apart (mean |H error| 0.049 / 0.032 against 0.19 / 0.28) and the
#: floor under a scanner (mean |H| within 0.2 m of the axis 2.8 -> 0.90); the scan-line tests
#: (tests/core/test_scan_lines.py) hold with this test, and noisy parallels gain (above).
INITIAL_JET_PIVOT = 3e-5
#: a quiet point keeps its jet as the result only if the jet's normal is within this many
#: degrees of its initial (2-jet) normal (core.scale.choose_model); elsewhere NR fits it. The
#: second guard against a jet the rank test let through (a 5:1 grid's three-column fits reach
#: pivots of 1e-4). Measured on the noise-free tuning shapes: at most 2.8 degrees (chirp),
#: p99.9 1.5; the jets of the grids above: 5-80 degrees.
JET_TILT = 5.0
#: ... and within this many where the jet's neighbours do not span the plane of the initial
#: normal (core.plane_spread.THIN_SPREAD): a strip of one scan line. A rotating scanner's noisy
#: ring is a flat strip of its cone, tilted from the ground by the ray's elevation (2.6-5.1 degrees
#: 20-40 m out): its quartic jet on 20 neighbours undid the initial normals' widening (3.6 -> 0.01).
JET_THIN_TILT = 1.0

# ----------------------------------------------------------------------------- neighbour search

#: points per leaf of the spatial-order search's tree (core.kernels.kdtree). Speed only
#: (the answer is the same for any value): a query visits the leaves its ball touches,
#: so smaller leaves test fewer points and more boxes. CPU s on a 100k torus, leaves of
#: 8 / 16 / 32: k = 16 0.25 / 0.23 / 0.23, k = 56 0.50 / 0.40 / 0.37, k = 226 1.05 / 0.96 / 0.85
#: (cKDTree's query alone: 0.39, 0.85, 4.0).
SEARCH_LEAF = 32
#: points per range of the spatial order (core.kernels.kd_order; speed only: finer ranges put a point by its nearest);
#: order + tree + k = 16 query, torus 100k / 1M (s): 32: 0.123 / 1.36, 2: 0.108 / 1.04, cKDTree's order: 0.131 / 1.52.
ORDER_LEAF = 2
#: a query whose previous point gives no radius (the first of a block, or a jump across
#: a gap) takes the k-th distance among the points of the smallest tree node of at least
#: this many points (or k) holding it; speed only. A larger node gives a tighter radius
#: and fewer candidates but costs more distances itself.
SEARCH_RADIUS_NODE = 64
#: a query first gathers the points within the previous point's k-th distance plus this
#: share of the step between the two (core.kernels.kdtree._query_block), and only if that
#: holds fewer than k points within the sure radius (the whole step: triangle inequality).
#: Speed only (any radius holding k points gives the same rows). CPU s of the search on a
#: 100k torus, one thread, share 1 (the sure radius at once) / 0.6 / 0.45 / 0.3: k = 15
#: 0.146 / 0.136 / 0.133 / 0.130, k = 56 0.242 / 0.224 / 0.208 / 0.202 (0: 0.157, 0.268).
SEARCH_REACH = 0.3
#: with k="auto" the search finds this many neighbours per point at first and the rows
#: that need more later (core.wide_neighbours.WidenableNeighbours): every stage before the
#: choice of scale reads at most 30 (core.border.BORDER_K), and the jet rule stops at
#: 15-28 neighbours at nearly every point of a noise-free cloud (at the next-to-last of
#: the sizes it is run on, it reruns with the whole list: it looks one ring ahead). A
#: noisy cloud is searched to k_search at once (core.scale.WIDEN_SHARE). Speed only.
#: CPU s of the search on a 100k torus: 16 0.14, 56 0.22, 226 0.69. 40 is the least that
#: keeps a cubic stopped at 20 final (sizes 15..40 held; it looks at the ring 28..40): the
#: 1-2 % of noise-free points at 28 or more are rerun on rows searched wider. Noise-free
#: torus, in one process, interleaved (loaded machine): 1M 26.4 -> 22.4 CPU s (56 -> 40:
#: 2.98 -> 2.72x NR k = 15, and 192 MiB less graph); 100k 2.30 -> 2.29 (the same).
SEARCH_WIDTH = 40

# ----------------------------------------------------------------------------- initial normals

#: k of the initial PCA normals when k is chosen automatically: the paper's k
PCA_K = 15
#: two points closer than this share of the distance to the k_initial-th neighbour are one
#: place (:func:`core.duplicates.near_copies`): a point written twice with float32 rounding
#: lies ~1e-5 of a spacing from itself, and its pair fills two of 15 neighbours with one
#: place (20k torus, every point twice 1e-6 apart: H error 0.08 instead of 1e-4); real
#: sampling, even 100:1 in density, keeps points orders of magnitude farther apart
NEAR_COPY = 1e-3
#: ... and twins are merged only when at least this share of the points has one: a few
#: twins among their neighbours' places cost nothing, while random (Poisson) sampling
#: leaves ~1.5e-5 of a surface's points that close to another (15 at 1M points), whose
#: merge would redo the whole search (a place of three or more copies is always merged)
NEAR_COPY_SHARE = 0.01
#: h of eq. 14 in units of the k-th neighbour distance, so no neighbour gets weight 0
THETA_REACH = 1.1
#: a neighbourhood is treated as collinear (no normal) when its middle eigenvalue is
#: this small relative to the largest
COLLINEAR = 1e-10
#: initial normals for k="auto" come from INITIAL_K0 x sqrt(noise) neighbours (at least
#: PCA_K), noise being the cloud's median of (RMS distance of the neighbours from their
#: osculating 2-jet) / (radius of the 15 neighbours). The jet normal's variance falls as
#: noise^2 / k^2 and its bias (third-order terms) grows as k, so the best k grows as
#: sqrt(noise). 182 puts 28 neighbours at noise 0.1 of the mean spacing and 40 at 0.2
#: (the radius of 15 neighbours is ~4.2 spacings): measured best on the torus, saddle and
#: ellipsoid at 0.05-1 spacing of noise.
INITIAL_K0 = 182.0
#: the initial normals' neighbourhood holds at most 1/INITIAL_SHARE of the cloud (core.scale.
#: initial_k): more of a closed surface is not local. A coarse sample reads as noise (the
#: 2-jets' residual is the surface's bend between samples): a 150-point torus measured
#: 0.05-0.06 and took 42-45 neighbours, its tube's far side among them, and k="auto" returned
#: inward normals at 99 % (seed 1) or a mix; 100 points, 56-79 neighbours. Only clouds under
#: INITIAL_SHARE x k_search (3200 points at k_search 320) can reach the cap.
INITIAL_SHARE = 10
#: with k="auto" and noise (initial normals wider than PCA_K) a point keeps its PCA_K normal
#: where the PCA_K normals of its wide neighbourhood agree less than this share of the
#: cloud's median (core.initial_normals.unfolded: the largest eigenvalue of their unsigned scatter):
#: at the 2-spacing rim of shapes_thin.thin_wedge the 58-neighbour plane lay across both faces
FOLD_SPREAD = 0.8
#: ... but not where its PCA_K nearest are a noisy scan line: as wide both ways across the line,
#: sqrt(lambda_min / lambda_mid) of their scatter above this, as they are narrow along it (sqrt(
#: lambda_mid / lambda_max) below core.plane_spread.LINE_SPREAD); there the small normals disagree
#: by the line's noise (a sphere in 30 rings of 300 points, noise 0.05 of their spacing: normals
#: 5.2 -> 1.3 degrees off at the 90th percentile; 10th percentile of the width 0.47-0.51 above
#: latitude 60). Thin shapes' rims at noise 0.1-0.3 spacing: 6-25 % of their points above 0.45,
#: spread along the rim (1st percentile 0.38-0.44): they keep falling back. Noisy surfaces at 15
#: neighbours (torus, 99th percentile): 0.11 / 0.20 / 0.30 / 0.48 at noise 0.1 / 0.2 / 0.3 / 0.5
#: spacing. The same width widens k="auto"'s initial normals (core.plane_spread.spanning_normals).
FOLD_FLAT = 0.45

# ----------------------------------------------------------------------------- automatic k (core.scale)

#: candidate neighbourhood sizes (about x1.4 apart). 320 on top of 226 (where the budget allows: up to 200k points):
#: with noise NR fits the largest candidate at most points of a smooth graph, and the direction e1 kept improving past
#: 226. Decided on the tuning and the private set (python -m core bench holdout --set tuning / private: geometric mean
#: of the error ratios 0.494 -> 0.478 and 0.470 -> 0.430, cells lost 1 -> 2 of 72 (worst 1.07x -> 1.01x) and 2 -> 1 of
#: 48), then checked on the hold-out: 11 -> 6 of 84 lost, worst 1.46x -> 1.37x, 0.500 -> 0.460. It costs H and K up to
#: ~10 % on the fast-curving chirp and saddle, and a noisy 100k cloud ~1.3x the CPU time.
AUTO_KS = (20, 28, 40, 56, 80, 113, 160, 226, 320)
#: neighbour entries (index + distance, 12 bytes) k="auto"'s lists may hold (~0.96 GB; core.neighbour_budget): the whole
#: graph widens to at most this / N columns, and the candidates stop where the lists of their fits would exceed it
#: (the held columns, and the wider rows as indices at the points that fit on them). 80M (it was 64M, every row whole)
#: lets a 1M-point cloud's noisy fits reach 320 at anchors (66.7M; 113 at every point: 77.7M)
NEIGHBOUR_BUDGET = 80_000_000
#: degree of the normal fit used by k="auto" (a cubic normal field: bias O(h^3))
AUTO_DEGREE = 3
#: width of the confidence intervals in standard deviations. The least-squares variance treats the neighbours' normals
#: as independent, but neighbouring estimated normals share most of their own neighbours, so their errors are
#: correlated and the variance is underestimated; 4 (not the textbook 2) compensates. Measured on the torus, saddle,
#: ellipsoid and a thin torus (r = 0.3) at noise 0-0.2 of the spacing.
GAMMA = 4.0
#: fold test (k stops growing where a ring of neighbours leaves the graph of a function over the local plane; see
#: core.kernels.scale). Share of a ring that may lie off the graph before k stops growing
FOLD_FRACTION = 0.2
#: a neighbour whose normal turns more than 70 degrees from the local mean normal is off the graph
FOLD_COS = 0.34
#: heights within this many RMS heights of the smallest neighbourhood are noise, not a fold. With noise of a whole
#: spacing, a test on the centre's own noisy normal (no margin) stopped a quarter of the points at k = 20.
FOLD_NOISE = 3.0
#: fewest off-graph neighbours that make a fold (a few turned normals in a small ring are noise)
FOLD_MIN_BAD = 3

# ----------------------------------------------------------------------------- the fit and its passes

#: a point whose fitted neighbours spread less than this across their main direction in the tangent plane
#: (sqrt(lambda_min / lambda_max) of their offsets, core.plane_spread) is not fitted: its neighbours lie along one
#: line, so its curvature across that line is noise over their tiny lever arms. Measured
#: (tests/core/test_plane_spread.py has the classes): k = 15 on random samplings of a torus: >= 0.31 (0.21 at k = 10,
#: 0.10 at k = 8); scan lines up to 6x wider apart than the along-line spacing: >= 0.5; 7x: 8 % of points 0.005-0.05 (H
#: error 8-9 against 0.02); 8x and 12x: median 0.013 (H error 54-77 against |H| 0.18, every point valid); a circle with
#: 1e-6 jitter: 0.006
THIN_SPREAD = 0.1

#: reweighting iterations of the robust fits (each one re-solves the least squares)
IRLS_ITERATIONS = 2
#: ... of the refinement passes after the first fit. Their input normals are the previous fit's, smooth, with the
#: outliers flagged and (robust mode) left out, so one reweighting finds the same weights. 2026-12-04, k="auto", 6000
#: points of torus, ellipsoid, saddle, chirp, sphere, cylinder, graded, range scan at noise 0.1/0.2/0.5 spacing and 0.2
#: with 3 % outliers (32 cells): H, K, e1 errors 0.83-1.03x those with 2 (the gains at 0.5 spacing and with outliers);
#: hold-out race unchanged (3/84 cells lost, geometric mean 0.456x), tuning race 0/72; noisy 100k torus (0.2 spacing)
#: 13 % less wall time. Zero reweightings: 30 % less time but 1.2-2.2x the errors with outliers.
IRLS_LATER = 1
#: ... and the fewest rows they fit on (k="auto"): of k >= 2 x ROWS_LATER neighbours, every (k // ROWS_LATER)-th by
#: distance (the same disc); a pass fits the previous fit's normals, each already a wide average, so half of them
#: determine the cubic as well. 2026-12-05: hold-out 0.445x -> 0.444x (3/84 lost; e1 1-3 % worse on 9 cells),
#: tuning 0.470x -> 0.471x, NF on a noisy 100k torus 6.5 -> 3.9 s; 80 rows: hold-out 5/84, tuning 0.481x; first fit
#: too 0.478x
ROWS_LATER = 160
#: k="auto"'s sparse centres (core.anchors): about ANCHOR_ROWS / k of the points with k >= 1.5 x ANCHOR_ROWS are fitted,
#: the others read the fits of the ANCHOR_BLEND nearest such anchors among their ANCHOR_REACH nearest (same k)
ANCHOR_ROWS = 80
ANCHOR_REACH = 24
ANCHOR_BLEND = 4
#: most NR refinement passes a user may ask for
MAX_PASSES = 20
# ----------------------------------------------------------------------------- the jet rule (issue 15, core.scale)

#: candidate sizes of the cubic-jet rule (about x1.4 apart; 15 = the paper's k, the
#: smallest that determines a cubic jet with a few degrees of freedom to spare)
JET_KS = (15, 20, 28, 40, 56, 80, 113, 160, 226, 320)
#: the two sizes whose residuals separate noise from model bias (see core.scale.noise_variance)
NOISE_KS = (15, 28)
#: neighbours over which the residual variances are pooled (a point's own 15-neighbour
#: fit has 5 degrees of freedom; pooling over 20 of them gives about 100)
NOISE_POOL = 20
#: interval width of the jet rule, in standard deviations. 3 intervals are tested at up to 8 sizes, so a textbook 2
#: rejects a size by chance at many points of a noisy cloud: measured on 7 stand-in surfaces at 0.1-0.5 spacing of
#: noise, 3 left 5-15 % of the points at small k (errors x1.5-15), 5 none; noise-free, 5 and 3 choose the same.
JET_GAMMA = 5.0
#: where the measured noise (sigma over the radius s of 15 neighbours) is below this, the data are nearly noise-free and
#: the position jet (which inherits no error of estimated normals) is the result; elsewhere the cubic normal field of
#: NR, refined, averages the noise better: measured on 7 stand-ins (noise-free the jet is 2-30x better than NR at the
#: same k; at 0.1-0.5 spacing NR is 1.2-1.8x better than the jet at the same k). Measured on the 13 hold-out and tuning
#: surfaces of core.bench.holdout (6000 points): noise-free data measure 0-0.0003 (99th percentile), 0.01 spacing of
#: noise 0.0017-0.0027 (median), 0.02 spacing 0.0035-0.0051, 0.1 spacing ~0.023. The earlier 0.006 kept noise of
#: 0.01-0.02 spacing on the cubic jet, where NR had 2.5-15x smaller H and K errors (torus at 0.01: H 0.0018 against
#: 0.027); 0.001 (about 0.004 spacing) leaves a 3x margin over noise-free data. An outlier that raises a point's
#: neighbours' residuals keeps them off the jet (the jet is not robust).
JET_QUIET = 0.001
#: the least noise the jet rule's intervals assume, over s, and (COORD_ROUNDING) over the size of the point's
#: coordinates: float64 rounds them to ~1e-16 of that size, so no measured noise below these is real. A cube on the
#: axes is exactly planar and measured 0, turned by 1e-12 rad 3e-16: intervals of zero width took other sizes (median
#: k 56 against 40, normals up to 8 degrees apart, |k| up to 0.83); races unchanged; tilted noise-free flat shapes:
#: normal error +0.01-0.03 degrees, H +3-17 %; 1e-14 or 1e-16 left the two apart. Beyond ~1000 s from the origin
#: rounding passes 1e-12 s: a 30 deg X scaled 0.1, 300 away, moved k at 50 of 12000 points; 4 ulps of |p|: none.
ROUNDING_NOISE = 1e-12
COORD_ROUNDING = 4 * 2.220446049250313e-16
#: when more than this share of the points measures noise above JET_QUIET, the jet rule
#: searches every point's whole list at once instead of the rows that grow past the
#: columns held (core.tuning.SEARCH_WIDTH): with noise most jets grow to the largest size
#: (noise 0.2 spacing on a torus: 96 % at 226), noise-free nearly none do. Speed only.
WIDEN_SHARE = 0.5
#: ... but only where the 15 neighbours reach less than this fraction of a radius of curvature (s |k|max): on 1000
#: points of a torus (15 neighbours span 0.65 of the tube's radius) NR's cubic normal field at the NF rule's k has a
#: quarter of the jet's H error, while on the 6000-point stand-ins (s |k| < 0.3) the jet at 15 wins noise-free.
JET_REACH = 0.4
#: in robust mode, points whose outlier score exceeds this stay out of the jets (which are least squares): 42 % of 3 %
#: outliers 2-8 spacings off a torus score below 4 (the flag) and, left in, stopped their neighbours' rule early: H
#: error x2.4 their clean baseline; x1.28 with 2.5, x1.26 with 2.0 (together with the k_init floor), x1.2 with 1.5
JET_SCORE = 1.5
#: polynomial degree of the position jets (noise-free, degree 2 at its best k lost 1.1-1.5x to degree 3 on the
#: stand-ins, and picking the degree per point by the smaller variance lost too)
JET_DEGREE = 3
#: higher degrees the jet rule tries where the data are quiet (noise below JET_QUIET), as (degree, neighbours), walked
#: in order. Noise-free, the cubic's error is the bias of the terms it lacks: on the 7 hold-out surfaces a quartic on
#: 20 neighbours had 20-50x smaller H, K and e1 errors than the cubic on 15 (a quintic on 28 100-300x, left out for
#: time). core.kernels.jet_degree takes them while their intervals agree: the quartic grows as the cubic does. Until
#: 2026-12-07 the quartic on 20 only: at noise of 1e-4-3e-3 spacing (float32 far from the origin, rounded exports) it
#: is too noisy, the cubic grew to 40-80 with its quartic's bias (+1.5 % H on a sphere at 1e-3), and the default was
#: 10-50x worse than noise-free or at 1e-2 (median |H| error / median |H|, 6 shapes: 1e-3 0.011-0.023 -> 0.001-0.004).
JET_DEGREES = ((4, 20), (4, 28), (4, 40), (4, 56), (4, 80), (4, 113))
#: a richer model whose residual variance per degree of freedom exceeds this many times the cubic's ends the richer
#: models (the walk goes on to the cubic): its wider neighbourhood holds an edge or a fold. Until 2026-12-07 1: at noise
#: of 1e-4 spacing both are noise on 5 degrees of freedom and the test a coin flip (77 % of a sphere fell to the cubic,
#: H error x150); 10 ~ the 99th percentile of F(5, 5); an edge's misfit is orders of magnitude.
JET_MISFIT = 10.0
#: interval width (sd) of the richer models' walk: 5 (JET_GAMMA) let the quartic grow to where its bias is 5 sd, on a
#: torus at 1e-3-3e-3 spacing of noise 1.3-1.5x the error of 3 (only quiet data walk; a chance stop costs a size)
JET_DEGREE_GAMMA = 3.0
#: with k="auto", refinement passes run only if NR (not the jet) fits at least this share of
#: the points with noise (noise-free, 0.1 % of a 5000-point torus was left: 4 points whose
#: mean turn let 2 passes through)
PASS_MIN_SHARE = 0.02

#: most NR refinement passes when k is chosen automatically (paper: 1). With the cubic
#: normal fit the refined normals are nearly unbiased, so a pass averages noise further,
#: and the change it makes to the normals decays geometrically. Once a pass changes them
#: by more than PASS_DECAY x the previous one, it is smoothing the shape itself (the
#: drift that remains noise-free) and is undone.
AUTO_PASSES = 4
PASS_DECAY = 0.7
#: ... and point by point (core.refinement._Held): where a pass turns a point's normal by more than
#: HOLD_TURN degrees and more than PASS_DECAY x its turn in the pass before, the point reports
#: the pass before (the passes and the rule's mean turns are unchanged). Noise averages away in
#: the first fit and pass (later turns ~1 degree); at a sharp edge the turns stay at 5-10 degrees
#: a pass. Measured (20k points, noise 0.2 spacing, seeds 0-4): 3, 5 and 8 give the 3-spacing
#: plate the same face agreement (to 0.03 %); the bunny's 50 % subsample |dH|/|H| is 0.182 with
#: the hold and without it
HOLD_TURN = 5.0
#: points the pass-stop rule is judged on (core.passes): about RULE_SAMPLE points of a larger cloud, chosen by a hash of
#: their coordinates (the same in any order and in tiles). The turns of a pass have a spread about 0.55 x their mean
#: (measured on noisy tori, saddles and ellipsoids), so 16384 points measure the mean to 0.4 %: only a pass within about
#: 1 % of the threshold can be judged otherwise than on all points, and such a pass turns the normals by a few
#: hundredths of a degree either way.
RULE_SAMPLE = 16_384
#: when the pass rule keeps one refinement pass and undoes the 2nd, points where the 2nd repeats
#: more than DRIFT_SHARE of the change the 1st made to H (pooled over the DRIFT_POOL nearest)
#: report the first fit's curvatures (core.drift). Decided on the tuning and private sets of
#: python -m core bench holdout (per-pass fits of the 6000-point races at 0.1/0.2/0.5 spacing;
#: geometric mean of the noisy cells' ratios to the best peer, before 0.620 / 0.664): 0.2
#: 0.611 / 0.657, 0.3 0.612 / 0.655, 0.4 0.614 / 0.658, 0.5 0.616 / 0.659, no cell worse at
#: any of them; pools of 20-80 within 0.003. After a later pass the test is not used: the
#: noise a pass leaves is smooth over the fit, and the next passes remove it in a repeating
#: pattern too (the 3rd pass repeats 0.3-0.74 of the 2nd's change on the 6000-point torus,
#: saddle and paraboloid, the 2nd 0.0-0.09 of the 1st's); stepping back from a 2nd or 3rd
#: pass at 0.5 cost the 20k torus (0.2 spacing) and saddle (0.5) 15-19 % of H and K
DRIFT_SHARE = 0.3
DRIFT_POOL = 40
#: |mu|^2 at or above this leaves no upward normal: the fit is rejected (core.frame)
MAX_TILT2 = 1.0 - 1e-6

# ----------------------------------------------------------------------------- per-point flags

#: a point whose distance to its neighbours' plane exceeds this many spreads is an outlier
OUTLIER_SCORE = 4.0
#: the unit of the outlier score adds this share of the neighbours' mean distance to
#: their centroid, so that a clean flat patch does not make every tiny offset look infinite
OUTLIER_FLOOR = 0.05
#: crease: normals spread (RMS, unit normals) above this and a linear fit leaving more
#: than CREASE_RATIO of that spread unexplained; the blended initial normals of a 30 deg
#: junction line spread 0.04-0.08 (0.15 caught 2-26 % of it: README, sheets that meet)
CREASE_SPREAD = 0.05
CREASE_RATIO = 0.25
#: ... and a residual above this many times the cloud's median residual (the noise)
CREASE_NOISE = 3.0

# ----------------------------------------------------------------------------- orientation: voted joins

#: core.orientation joins two parts of at least VOTE_SIZE points by the sum of the evidence
#: of all the edges between them, not by their strongest edge (core.kernels.sign_evidence.
#: voted_signs), and parts VOTE_GROWTH x larger again by a sum, and so on up. Measured on
#: the thin shapes at noise 0.2 spacing (20k points, seeds 0-4, k = 15 and "auto"): without
#: the vote, k="auto" flipped the whole bottom of a 3-spacing plate (seed 2: 50 %) and a
#: fifth of a 2-spacing tube (seed 1: 80 %); 16 to 64 all fix both; 2-8 vote small patches
#: at a rim, whose seams are too short for a sum to beat one edge (-0.2 % on the bowl).
VOTE_SIZE = 16
VOTE_GROWTH = 4
#: core.orientation.resettle's local majority reads the evidence of each point's RESETTLE_K
#: nearest where the plan searches that many (k="auto"; an integer k: its k, core.refinement.
#: wider_ring), on the refined normals (the noise gate still from the ORIENT_K nearest), not
#: the ORIENT_K the forest joins: at a sharp rim the 10 nearest of a blended point are mostly
#: its like-blended neighbours; 30 reach the clean faces beyond. Measured on the thin shapes
#: at noise 0.2 spacing (20k points, seeds 0-9, face share), k="auto": tube 99.890-99.965 ->
#: 99.920-99.975 %, plate 99.410-99.665 -> 99.435-99.685 % (with FOLD_TRUST). At k = 15 a
#: search of 30 gave the plate 99.39-99.62 -> 99.45-99.655 % but cost NR on 100k points 1.3x
#: its CPU time (left out); 15 and 20 gain about half as much
RESETTLE_K = 30
#: with k="auto" an edge's evidence is scaled by its points' flatness, 1 - FOLD_TRUST x median
#: offset / neighbourhood radius (core.orientation._evidence). At the rim of a part 2 spacings
#: thick (the thin end of shapes_thin.thin_wedge) k="auto"'s wide initial normals lie along the
#: faces' (a blend of top and bottom), their noise gate (the median offset) silences the chord
#: test, and Hoppe's term joined top and bottom as one side, strongly: at noise 0.2 spacing the
#: face share was 77.4-98.975 % (seeds 0-9), with the scaling 98.73-99.435 %. 1 kept the plate
#: a little better (k=15 seeds 5, 9: +0.05-0.08 %) but left the wedge's seed 9 at 95.3 %; 3
#: and 4 cost the 2-spacing tube 2-7 % at the orientation stage. On the integer-k path (k=15
#: PCA normals) it cost the plate and the bowl 0.02-0.1 %: not used there
FOLD_TRUST = 2.0
#: core.orientation.resettle re-decides flipped patches by their seam: a patch joins graph
#: neighbours whose signed normals are within acos(PATCH_COS) and whose chord is within
#: PATCH_TILT (sine) of both tangent planes (so it stops at a rim), PATCH_ROUNDS times, patches of
#: at most PATCH_MAX points (a whole face is the spanning forest's). The thin shapes (20k points,
#: noise 0.2 spacing, seeds 0-9, k=15, face share), with the raw-offset weight of Hoppe's term:
#: plate 99.395-99.615 -> 99.445-99.675 %, wedge 98.725-99.655 -> 99.435-99.680 % (seed 1's
#: flipped patch of 120 points at the thin end); offline, cos 0.8 / tilt 0.25-0.4 the same to
#: 0.01 %; without the tilt test the patches grew round the rims into whole faces (19 911 of
#: 20 000 points in one)
PATCH_COS = 0.9
PATCH_TILT = 0.5
PATCH_ROUNDS = 2
PATCH_MAX = 1000
#: with k="auto" (core.orientation.resettle(trust=True)) only points whose flatness trust (FOLD_TRUST)
#: exceeds this join a patch: at the wedge's 2-spacing thin end auto's smeared rim normals (trust
#: ~0.4; a face's ~0.8) chained a flipped patch of its top into the bottom (one patch of 19 933
#: points, seed 9); at 0.6 the patch is its own 55 points and flips
PATCH_TRUST = 0.6

# ----------------------------------------------------------------------------- threads

#: OpenMP's wait policy for numba's worker threads when the environment sets none (core._threads; numba's threading
#: layer is libgomp here). libgomp's default lets an idle worker spin ~300k times after every parallel loop before it
#: sleeps, so each serial stretch between two loops (numpy, the spanning forest, cKDTree's build) also burnt the other
#: core. One NR k = 15 estimate of a 100k torus, CPU s with 2 threads: 0.96 spinning, 0.71 passive (1 thread: 0.65).
#: Against the bare kNN search, same process, median of 8 interleaved pairs, load 10 on 2 cores: wall 2.05 / 2.47 ->
#: 1.51 / 1.90, CPU 1.89 / 2.20 -> 1.40 / 1.65 (two processes each). The results are the same bits (the policy only
#: decides how threads wait).
OMP_WAIT_POLICY = "PASSIVE"
#: numpy's large arrays on 4 KiB pages, not transparent huge pages (core._pages, set at ``import core`` unless
#: NUMPY_MADVISE_HUGEPAGE is in the environment). On this 2-core KVM guest with free page reporting a fresh huge page
#: cost 2-4 ms (host faults); NR k = 15 on the bench's 1M torus, processes alternating with NUMPY_MADVISE_HUGEPAGE=0
#: (load ~7): estimate 9.6-10.3 -> 6.4-7.1 CPU s, the bare kNN search in the same processes 7.3-7.5 -> 6.6-6.8, NR /
#: kNN CPU 1.16-1.22 -> 1.00. On bare metal huge pages are cheap to fault and 4 KiB pages cost more faults: not
#: measured there. Same bits either way.
NUMPY_HUGEPAGES = False
