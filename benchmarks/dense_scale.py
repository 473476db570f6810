"""Radar at scale (issue 14): the in-process chain on the dense scenes, one table row per
target density; exit code 1 when a quality goal of the issue fails.

Run: .venv/bin/python benchmarks/dense_scale.py [--scenes dense dense300 dense1000]
     [--scans N] [--seed N] [--profile]

Each scene (scenarios/<name>.toml, written by benchmarks/dense_scene.py) goes through
common.wire.radar_chain's cores in one process: simulator, channel plotter and
elementary tracker of every base, global fusion, with the wall time of each service per
scan (CPU of this process; the services are separate processes in a deployment, so these
are the per-service costs). Quality of the confirmed global tracks against the truth
after a 30 s warm-up (GOSPA assignment, cut-off 2 km): missed targets and false tracks
per scan (as % of the targets present), number switches and breaks per 100 targets over
the run, RMSE / PCRLB (median over targets) and mean position NEES (3 dof). The log-log
slope of each service's cost against the number of targets is printed when several
scenes run.

Goals (issue 14, checked for scenes of >= 300 targets): missed < 2 % and false < 1 % per
scan, switches < 1 per 100 targets, RMSE/PCRLB <= 1.5, mean NEES within a factor 1.5 of
the dimension (2-4.5 for the 3-D position).

Measured 2026-11-23 (seed 1, 120 s, 2 shared cores at load 10-27; CPU ms per scan):

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  before (the fusion of 0cd7502):
  dense          120     6.3    12.7   73.7   10.8  0.6 (0.5%)   1.6 (1.4%)    1.67   5.00   0.92     3.08
  dense300       300     9.3    22.1  167.2    5.0  2.6 (0.9%)   4.4 (1.6%)    6.33   4.00   0.97     3.82
  dense1000     1000    23.9    72.2  867.5    1.0 76.5 (8.2%) 113.2 (12.2%)  58.20  22.20   2.36    66.91
  after (typed arrays, closed-form SLR, 004 on confirmed tracks, duplicate merge):
  dense          120     6.7    13.8   57.0   12.9  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     8.9    21.6  116.8    6.8  1.5 (0.5%)   2.1 (0.8%)    1.00   3.00   0.92     3.77
  dense1000     1000    23.0    69.8  442.4    1.9 11.3 (1.2%)  29.6 (3.2%)    9.00   4.80   1.01     7.71
  log-log slope of the cost per scan, 120 -> 1000 targets: plotter 0.59, tracker 0.77,
  fusion 0.97. Failing goals: dense300 switches 1.00 (< 1 asked); dense1000 false
  3.2 %, switches 9 per 100 targets, NEES 7.7 (its false tracks: 80 % hold one target's
  elementary tracks with the altitude 2-3 km off at sigma_z ~ 165 m).

Measured 2026-11-26 (seed 1, 120 s, 2 shared cores at load 1.5-8; CPU ms per scan; two
interleaved runs each, the faster; every gtracks message of both scenes is identical bit
for bit before and after, hence the same quality columns):

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  before (a5ff39b):
  dense          120     2.1     3.9   18.3   41.0  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     3.0     6.7   44.2   18.5  1.5 (0.5%)   2.1 (0.8%)    1.00   3.00   0.92     3.77
  after (block pruning by Taylor bounds over the leaf centres, children tested per
  parent; one call over all bases for the decorrelation, the gate [48] and the v_b
  rows; the gate by the heaviest component first; norm3; IMM mixing and band moments
  of live bands only; connected components of the plotter in numpy; gtracks by tolist):
  dense          120     1.4     3.8   12.3   57.2  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     2.4     6.8   27.0   27.6  1.5 (0.5%)   2.1 (0.8%)    1.00   3.00   0.92     3.77
  This machine runs the chain about 3.2x faster than the one of 2026-11-23 (dense
  before: 41.0x real here, 12.9x there). End to end 1.40x on dense (fusion -33 %),
  1.49x on dense300 (fusion -39 %): about 18x real on the 2026-11-23 machine, short of
  issue 14's 20x there; 57x here.

Measured 2026-11-26, ghost tracks (seed 1, 120 s, 2 shared cores, two scenes at a time;
CPU ms per scan):

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  before (304645d):
  dense          120     1.8     4.7   14.6   47.6  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     3.0     8.4   31.9   23.1  1.5 (0.5%)   2.1 (0.8%)    1.00   3.00   0.92     3.77
  dense1000     1000     9.1    27.3  110.3    6.8 11.3 (1.2%)  29.6 (3.2%)    9.00   4.80   1.01     7.71
  after b1fc412 (duplicates in measurement space: a track whose elementary tracks another
  track explains, common.radar.global_merge):
  dense          120     1.6     4.3   13.8   50.9  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     2.8     7.4   29.2   25.3  1.5 (0.5%)   2.1 (0.8%)    1.00   3.00   0.92     3.77
  dense1000     1000     8.2    24.3  105.2    7.3 11.3 (1.2%)  13.4 (1.4%)    7.40   5.20   0.98     7.53
  after (and a track of two targets' elementary tracks, each explained by another track,
  deleted: global_merge.explained):
  dense          120     1.5     3.9   12.8   55.1  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     2.3     6.5   27.5   27.5  1.5 (0.5%)   2.1 (0.8%)    0.67   3.00   0.92     3.77
  dense1000     1000     7.9    23.5   99.6    7.6  8.7 (0.9%)   8.0 (0.9%)    7.70   5.20   0.99     6.02
  The false tracks of dense1000 (global_merge's module doc): pairs of two targets'
  elementary tracks at one azimuth, located at a fictitious altitude with sigma_z
  50-250 m, then holding one or both targets' bases there. Goals now met: dense300
  switches (0.67), dense1000 missed 0.9 % and false 0.9 %. Still failing: dense1000
  switches 7.7 per 100 targets and NEES 6.0; its breaks went 4.8 -> 5.2. Tried and
  not kept: a joint coherence test (ranges, azimuths and bistatic velocities of all
  members) of module 62's step 5: dense1000 false 3.1 -> 2.4 % over 60 s, but
  dense300 RMSE/PCRLB 0.92 -> 0.93 and NEES 3.77 -> 3.78.

Measured 2026-11-26, number switches of dense1000 (seed 1, 120 s, 2 shared cores; the
elementary tracks labelled with the truth projected into their base, each switch with
the fusion events before it). Of the 77 switches (35 in the 30 s warm-up, which the
switch count includes): 41 are flip-flops of 7 pairs of tracks on two aircraft 0.2-1 km
apart in plan, each track holding its own target's elementary tracks with 20-100 m plan
error but 0.2-1.3 km altitude error, so the 3-D GOSPA assignment crosses over and back
(one pair: 16); 8 a target first scored on a neighbour's or a mixed track, then on its
own new track (t = 6-17 s, one at 61 s); 16 the track matched to the target removed by
global_merge.explained (8 dissolved two-target tracks, 8 merged, 7 of them into the
target's new track); 3 a track deleted after coasting and replaced; 9 after breaks or
other swaps. 73 of the 77 had another aircraft within 2 km in plan. Fix of the merged
ones (global_merge.number_kept): a tentative track that explains a confirmed one takes
its number:

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  after:
  dense          120     1.4     3.6    12.5   57.2  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     2.3     6.7    27.5   27.4  1.5 (0.5%)   2.1 (0.8%)    0.67   3.00   0.92     3.77
  dense1000     1000     7.8    22.9    98.6    7.7  8.7 (0.9%)   8.0 (0.9%)    7.10   5.20   0.99     6.02
  Every other quality column equal to full precision (dense, dense300: the same
  gtracks); dense1000 switches 7.7 -> 7.1 (2 of the 16 left). Moving the confirmation
  with the number (the track reported at once): switches 7.1 and breaks 4.6, but false
  7.967 -> 7.978 per scan and NEES 6.0245 -> 6.0261; not kept. The flip-flops of close
  pairs (more than half) come from the altitude error of one receiver's geometry.

Measured 2026-11-26, ambiguous memberships (seed 1 unless said, 120 s, 2 shared cores; CPU
ms per scan). Traced first (every elementary track against the truths): two aircraft
540 m apart in plan, 1.7 km in altitude; at t = 5 s base b2's elementary tracks swapped
and both global tracks, 2 s old, took the other aircraft's (range-rate 8-10 sigma off
the truth, inside [48] of a young track); the bands collapsed to one 0.6-1.1 km off with
sigma_z 190-340 m, which the other three bases (ranges within 1 sigma of the truth at
both altitudes) never corrected: NEES 10-170, then 28 switches of that pair. Fix
(common.radar.global_assoc.ambiguous_members): a base whose elementary tracks of two
tracks pass [48] against each other's track is used by neither this scan.

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  before (62f13e8):
  dense1000     1000     8.2    24.5    98.4    7.6   8.7 (0.9%)   8.0 (0.9%)    7.10   5.20   0.99     6.02
  dense1000 s2  1000     7.9    23.5    97.2    7.8  14.3 (1.5%)  16.0 (1.7%)    7.10   5.60   1.01     4.72
  after:
  dense          120     1.6     4.3    15.5   46.7   0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.09
  dense300       300     2.6     7.3    32.2   23.8   1.5 (0.5%)   2.1 (0.8%)    0.67   3.00   0.92     3.23
  dense1000     1000     8.2    24.6   113.8    6.8   8.4 (0.9%)   7.5 (0.8%)    4.70   4.90   0.99     3.36
  dense1000 s2  1000     8.0    24.1   110.2    7.0  12.4 (1.3%)  13.5 (1.4%)    3.80   4.10   1.01     3.25
  (dense and dense300 before: NEES 3.07 and 3.77, every other quality column equal.)
  The 47 switches left (seed 1): 35 trade two truths between two live tracks, 19 of
  them by t = 15 s; in 10 of those the track that lost the truth is still consistent
  with it (position NEES <= 11.3, chi-square 3 dof at 0.99): two aircraft under 1 km
  apart in plan whose honest altitude sigma is 0.5-1.1 km, which the Euclidean 3-D
  assignment of the scoring trades (e.g. t = 9 s: truth 67 at NEES 0.6 from its track,
  moved to a track at NEES 254 because the pair's summed squared errors were smaller).
  The rest: a target first scored on a neighbour's track and then on its own (young)
  track, and 8 track replacements (a track lost, a new one started).
  Then a scan counts towards confirmation only when the track was located (module 64's
  chi-square test passed; a track of two targets' elementary tracks fails it):
  dense1000     1000     7.7    23.1   108.9    7.2   8.4 (0.9%)   7.4 (0.8%)    4.40   4.70   0.99     3.36
  dense1000 s2  1000     7.6    22.7   104.6    7.4  12.4 (1.3%)  12.5 (1.3%)    3.60   3.90   1.01     3.25
  (dense and dense300: every quality column unchanged.)
  Tried and not kept (measured before this fix): q_z 0.1 and 0.01 m^2/s^3 (more
  altitude integration): switches 7.1 -> 7.7, 8.3; stricter confirmation (confirm_cycles 5, 8; confirm_bases 3):
  switches 5.4, 5.0, 5.5 but missed 1.2, 1.6, 1.1 %.

Measured 2026-11-26, the NEES of dense1000 (seed 1, 120 s; every GOSPA pair with the
track's members labelled by the nearest truth projected into each base). The mean of
6.02 is a mean over targets of each target's mean: median 2.53, 3.73 without the 5
worst targets (1073, 377, 331, 289, 240). Pairs whose track holds another target's
elementary track at some base: 1.3 % of the samples, 37 % of the summed NEES (mean
112, altitude part 55); with only pure pairs the mean would be 3.82. The worst were
all the same mechanism at b2 (Tx at (45, 10) km, where the targets near its
transmitter get their altitude from b2's range and v_b alone): either b2's elementary
track swapped to a neighbour after a crossing in b2's space (member number unchanged,
e.g. 868 / 444 at t = 54: v_b 15 m/s off in one scan), or module 62 extended two
parallel aircraft 540 m apart in plan (1000 and 467, 1.7 km apart in altitude) with
each other's b2 track while the altitude was open. The gate [48] of the swapped track
alone passes (the manoeuvre component covers the jump) and the EKF explains it by a
false vz (up to 100 m/s with sigma_vz 1.6 m/s) and altitude (errors of 0.5-1.9 km at
sigma_z 30-130 m). Not the band pruning or the altitude prior: those tracks were
consistent until the swap. Fix (common.radar.global_filter): the leave-one-out test
of the v_b rows of [49] (global_ekf.vb_deletion_residuals; chi-square(1) at the
threshold of the largest of n rows); the worst row that fails is left out of modules
64-65 and its membership dissociated, module 63 re-associates from the track's state.
About 2.5 drops per scan on dense1000, 0.1 on dense. CPU ms per scan; two runs per
seed, before and after interleaved:

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  seed 1, before (62f13e8):
  dense          120     1.3     3.6    11.9   59.7  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     2.2     6.5    25.2   29.5  1.5 (0.5%)   2.1 (0.8%)    0.67   3.00   0.92     3.77
  dense1000     1000     7.6    22.6    96.0    7.9  8.7 (0.9%)   8.0 (0.9%)    7.10   5.20   0.99     6.02
  seed 1, after:
  dense          120     1.3     3.4    11.9   60.5  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     2.2     6.2    27.0   28.2  1.5 (0.5%)   2.1 (0.8%)    0.67   3.00   0.91     3.21
  dense1000     1000     7.5    22.3    96.7    7.9  7.6 (0.8%)   6.5 (0.7%)    4.70   4.70   0.97     3.81
  seed 2, before:
  dense          120     1.3     3.4    11.6   61.8  0.7 (0.6%)   1.0 (0.9%)    0.83   3.33   0.91     2.86
  dense300       300     2.2     6.2    26.0   29.1  2.1 (0.8%)   3.0 (1.1%)    1.33   2.33   0.95     3.75
  dense1000     1000     7.4    22.1    93.8    8.1 14.3 (1.5%)  16.0 (1.7%)    7.10   5.60   1.01     4.72
  seed 2, after:
  dense          120     1.3     3.5    12.5   57.7  0.7 (0.6%)   1.0 (0.9%)    0.83   3.33   0.94     2.88
  dense300       300     2.3     6.5    28.1   27.1  1.6 (0.6%)   2.5 (0.9%)    1.33   2.00   0.95     3.12
  dense1000     1000     7.8    23.3    99.3    7.7 12.1 (1.3%)  13.2 (1.4%)    6.30   4.90   0.99     3.91
  dense seed 1: the same to full precision but NEES 3.0739 -> 3.0725. dense seed 2
  RMSE/PCRLB 0.913 -> 0.939: two crossing aircraft (60, 74) whose mixed tracks of t = 4
  are now mended (b4 swapped) and kept, so they are scored from t = 5-6 instead of on
  the new tracks of t = 14-15, i.e. earlier in their convergence; both stay below 1.0.
  Seeds 3 and 4: dense the same but NEES 3.135 -> 3.137 (seed 3), RMSE/PCRLB 0.903 ->
  0.908 and NEES 3.058 -> 3.049 (seed 4); dense300 better or equal in every column. dense1000 seed 1: switches returning to an
  earlier track (flip-flops) 30 -> 14, in the warm-up 34 -> 17 of 71 -> 47; NEES without
  the 5 worst targets 3.10. What is left: the pair 467 / 239 crossing at t = 37-41 while
  467's track still holds 1000's b2 track from module 62 (it is dropped at t = 55, when
  the v_b of the two b2 tracks have drifted apart), 0.58 of the mean NEES; module 62's
  choice between two gated tracks of one base while the altitude is open is not
  decided by any measurement of that scan. Tried and not kept: the test on confirmed
  tracks only (dense1000 switches 6.8, dense seed 2 breaks 3.33 -> 4.17); a row failing
  in every mixture component instead of the heaviest band (dense1000 NEES 3.98,
  switches 6.3); dropping only when removing the worst row makes the others pass
  (dense1000 NEES 3.87 and 3.97 on seeds 1 and 2, false 6.8 and 13.6); the test at
  0.9999 instead of gate_prob (two_targets and crossing unchanged, but dense1000 NEES
  3.93 and 4.42 on seeds 1 and 2); extending a new track in module 62 only to a base
  with a single gated elementary track (dense1000 switches 5.5). The built-in scenes
  (benchmarks/global_consistency.py, 16 runs): two_targets ANEES 3.03 -> 3.04, crossing
  2.98 -> 3.00, every target inside its 95 % interval at >= 98 % of the times; pooled
  RMSE/PCRLB of target 1 1.23 -> 1.24 and 1.25 -> 1.28 (one false drop at t = 64 in
  seed 1 of both scenes, same noise: a v_b row of 3.8 sigma that carried an altitude
  correction), target 2 0.96 -> 0.97 and 1.19 -> 1.19.

Both fixes together (the ambiguous memberships and the v_b leave-one-out test, merged
2026-11-26; CPU ms per scan, 2 shared cores):

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  seed 1:
  dense          120     1.2     3.4    13.3   55.6  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.08
  dense300       300     2.1     6.3    28.9   26.8  1.5 (0.5%)   2.1 (0.8%)    0.67   3.00   0.92     3.21
  dense1000     1000     7.6    22.5   109.3    7.2  7.6 (0.8%)   6.5 (0.7%)    4.30   4.40   0.98     3.03
  seed 2:
  dense          120     1.2     3.4    13.3   55.7  0.7 (0.6%)   1.0 (0.9%)    0.83   3.33   0.93     2.87
  dense300       300     2.1     6.3    28.8   26.8  1.6 (0.6%)   2.0 (0.7%)    1.33   2.00   0.95     3.12
  dense1000     1000     7.9    23.3   111.1    7.0 11.8 (1.3%)  11.0 (1.2%)    3.50   3.80   1.00     3.70
  Each alone, dense1000 seeds 1 / 2: ambiguity NEES 3.36 / 3.25, switches 4.4 / 3.6,
  false 0.8 / 1.3 %; leave-one-out NEES 3.81 / 3.91, switches 4.7 / 6.3, false 0.7 /
  1.4 %. Through the processes (benchmarks/load.py --scene dense1000, ambiguity fix
  only, load 3-6 from other work): 2x kept up, 0 lost, end to end p50/p99 196/3224 ms;
  4x kept up, 0 lost, 1711/5153 ms (the cycles that initialise the 1000 tracks).

Measured 2026-11-26, the false tracks of dense1000 seed 2 (120 s; every elementary track
of every false confirmed track, after 30 s, labelled with the nearest truth projected
into its base, Mahalanobis distance of its [r_b, v_b, theta] at chi-square(3) 0.999).
Of the 988 false track-scans (11.0 per scan):
  (d) 390: no member near any truth, 382 of them with every member in pure prediction at
      its base: aircraft that left the scene (t_off of the scenario; the same 70-odd on
      every seed), whose elementary tracks coast up to [radar.tracker] max_coast = 5
      scans while the global track stayed confirmed: 3.9 per scan on every seed;
  (a) 467 (15 tracks): one target's elementary tracks (2-4 bases) with the track's
      altitude off by > 1.5 km (2.3-12 km) and no other track on that target: 7 tracks
      (416 scans, 10 / 29 / 141 / 306 / 339 / 674 / 918) at 5-70 sigma_z (sigma_z 115-540
      m, ranges 36-57 km), i.e. dishonest: the global_merge ghost mechanism (a start or a
      phase on two targets' elementary tracks at a fictitious altitude) kept with the
      target's own bases; 51 scans (8 tracks: 711, 733, 509, ...) within 3 sigma_z
      (sigma_z 1-2 km at 47-60 km from the receiver): the geometry of one receiver;
  (c) 93: a duplicate of a target held by another track;
  (b) 38: a track of two targets' elementary tracks.
Fix of (d) (common.radar.global_status): a confirmed track none of whose contributing
elementary tracks was updated for coast_cycles = 2 consecutive cycles is reported
coasting (001's pure prediction); one cycle (coast_cycles 1) also reports the present
targets that every base missed once: dense1000 seed 2 breaks 3.8 -> 4.3, missed 11.8 ->
11.9. Two shared cores; CPU ms per scan of the after runs (the before rows are the table
above):

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  seed 1, after:
  dense          120     1.4     3.5    13.6   54.3  0.6 (0.5%)   0.2 (0.2%)    0.00   5.00   0.92     3.08
  dense300       300     2.6     6.5    29.4   26.0  1.5 (0.5%)   0.6 (0.2%)    0.67   3.00   0.92     3.21
  dense1000     1000     8.9    22.9   111.3    7.0  7.7 (0.8%)   2.5 (0.3%)    4.30   4.40   0.98     3.02
  seed 2, after:
  dense          120     1.5     3.6    14.1   52.2  0.7 (0.6%)   0.3 (0.2%)    0.83   3.33   0.93     2.87
  dense300       300     2.6     6.7    31.6   24.4  1.6 (0.6%)   0.5 (0.2%)    1.33   2.00   0.95     3.12
  dense1000     1000     9.1    23.4   111.4    7.0 11.8 (1.3%)   7.1 (0.8%)    3.50   3.80   1.00     3.70
  dense1000 seed 3, before / after: false 6.66 -> 2.69 per scan (0.7 -> 0.3 %), every
  other column equal (missed 7.07, switches 4.5, breaks 3.6, RMSE/PCRLB 1.01, NEES 3.55).
  Every other column equal to full precision (dense and dense300 seeds 1, 2; dense1000
  seeds 2, 3) but dense1000 seed 1: missed 7.622 -> 7.667 per scan (4 target-scans in
  90 scans) and NEES 3.032 -> 3.023. The built-in scenes (benchmarks/global_consistency.py,
  two_targets and crossing, 16 runs each): identical output. What is left on seed 2 (7.1 per
  scan, 0.8 %): class (a), the altitude of one receiver's geometry held at a wrong value
  with a sigma_z too small, 4.6 per scan, of which 0.6 honest. Traced from birth: track
  10 started at t = 2 on b1's track of aircraft 38 and b2-b4's of 674, located at t = 3
  6.3 km too high with sigma_z 93 m; 38's track left at t = 11, the other three kept
  passing [48] at that altitude (dz 5.7 km, sigma_z 45-160 m, to t = 101). Track 141:
  b2's track of aircraft 11 with b1, b3, b4's of 827, z 5.7 km too high at sigma_z 176 m
  from t = 4, 11's track held until t = 51. Track 306: aircraft 285's b1, b2, b4 tracks
  and 940's b3 track, z right (-0.2 km, sigma_z 0.76 km) until 940's track left at t = 7,
  then 4.3 km too high at sigma_z 0.3-0.6 km to the end, every member at 1-7 of [48]. The
  altitude information of a band comes from another target's elementary track and is
  kept after that track is dissociated; the remaining bases' [48] cannot refute it
  (global_merge's module doc: a 3 km altitude error costs 3-8 of [48]). Not fixed here.

Measured 2026-11-26, after merging the coasting report: the ambiguous memberships
withheld only when the swapped pairing is about as likely as the held one (summed
[48] gammas within the chi-square(1) quantile of gate_prob; without that condition
every crossing of two settled tracks in crossing.toml was withheld: RMSE/PCRLB over
seeds 1-3 0.79 -> 0.87, now 0.79; two_targets 0.78 either way):

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  dense1000     1000     8.0    23.6   118.3    6.7  7.5 (0.8%)   2.4 (0.3%)    4.00   3.90   0.97     3.08
  dense1000 s2  1000     8.6    25.8   127.1    6.2 11.8 (1.3%)   7.1 (0.8%)    3.70   4.10   1.00     3.70
  dense300 seeds 1, 2 and dense seed 1: every quality column as before; dense seed 2
  RMSE/PCRLB 0.93 -> 0.94.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from common.deploy.config import parse, section
from common.evaluation.pcrlb import Evaluation, score_targets
from common.radar.global_fusion import FusionParams
from common.sim.simulator import load_scenario, run_scenario
from common.wire.radar_chain import RadarChain
from common.wire.radar_messages import gtracks_message, plots_of

REPO = Path(__file__).resolve().parents[1]
WARMUP = 30.0
GATE_C = 2000.0


@dataclass
class Row:
    """One scene's measurements."""

    name: str
    targets: int
    scans: int
    ms: dict[str, float]
    missed: float
    false: float
    switches: float
    breaks: float
    rmse_ratio: float
    nees: float
    present: float

    def goals(self) -> list[str]:
        """The issue's quality goals this row fails (empty: all met)."""
        bad = []
        if self.missed >= 0.02 * self.present:
            bad.append(f"missed {self.missed:.1f} per scan >= 2 % of {self.present:.0f}")
        if self.false >= 0.01 * self.present:
            bad.append(f"false {self.false:.1f} per scan >= 1 % of {self.present:.0f}")
        if self.switches >= 1.0:
            bad.append(f"switches {self.switches:.2f} per 100 targets >= 1")
        if self.rmse_ratio > 1.5:
            bad.append(f"RMSE/PCRLB {self.rmse_ratio:.2f} > 1.5")
        if not 3 / 1.5 <= self.nees <= 3 * 1.5:
            bad.append(f"mean position NEES {self.nees:.2f} outside [2, 4.5]")
        return bad


def run(name: str, seed: int, scans: int | None, fusion: dict[str, Any] | None = None) -> Row:
    """The chain on scenarios/<name>.toml, scored; `fusion`: keys of [radar.fusion] set
    over the file's (benchmarks/seed_vs_mixture.py)."""
    import tomllib

    from common.evaluation.pcrlb import base_information
    from common.sim.scenario import radar_scene
    from common.wire.sim_messages import truth_state

    path = Path(name) if name.endswith(".toml") else REPO / "scenarios" / f"{name}.toml"
    name = path.stem
    doc = tomllib.loads(path.read_text())
    doc.setdefault("radar", {}).setdefault("fusion", {}).update(fusion or {})
    cfg = parse(doc, path)
    scn = load_scenario(doc)
    chain = RadarChain(cfg)
    cost = {"plotter": 0.0, "tracker": 0.0, "fusion": 0.0}
    ev = Evaluation(c=GATE_C, gamma=GATE_C)
    missed, false, present, n_scans = [], [], [], 0
    for t, msgs in run_scenario(scn, cfg.bases, [], seed, scans):
        n_scans += 1
        truth = next(m for k, m in msgs if k == "sim/truth/radar")
        out = []
        for key, msg in msgs:
            if not key.startswith("radar/plots/"):
                continue
            base = msg["base"]
            t0 = time.process_time()
            fused = chain.plotters[base].push(msg["channel"], msg["t"], plots_of(msg))
            t1 = time.process_time()
            cost["plotter"] += t1 - t0
            for tf, f in fused:
                tracks = chain.trackers[base].step(tf, f)
                t2 = time.process_time()
                cost["tracker"] += t2 - t1
                out += [gtracks_message(g) for g in chain.fusion.push(base, tracks)]
                t1 = time.process_time()
                cost["fusion"] += t1 - t2
        g = next((m for m in out if m["t"] == t), {"tracks": []})
        conf = [k for k in g["tracks"] if k["status"] == "confirmed"]
        ev.add(t, np.asarray(truth["id"]), truth_state(truth),
                     np.array([k["id"] for k in conf], dtype=np.int64),
                     np.array([k["x"] for k in conf]).reshape(-1, 6),
                     np.array([k["P"] for k in conf]).reshape(-1, 6, 6))
        res = ev.metrics.gospa_series[-1]
        if t >= WARMUP:
            n_truth = len(truth["id"])
            present.append(n_truth)
            missed.append(n_truth - res.rows.size)
            false.append(len(conf) - res.rows.size)
    p = section(cfg, "radar.fusion", FusionParams)
    sc = score_targets(ev, np.array([b.tx for b in cfg.bases]), np.array([b.rx for b in cfg.bases]),
                       base_information(radar_scene(cfg), cfg.bases), p.q, p.q_z, np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2]), WARMUP)
    s = ev.metrics.summary()
    n_t = len(ev.truth)
    ratio = np.array([v.rmse / v.bound for v in sc.values()])
    nees = np.array([v.nees_pos for v in sc.values()])
    return Row(name, n_t, n_scans, {k: 1e3 * v / n_scans for k, v in cost.items()},
               float(np.mean(missed)), float(np.mean(false)), 100.0 * s.switches / n_t,
               100.0 * s.breaks / n_t, float(np.median(ratio)), float(np.mean(nees)),
               float(np.mean(present)))


def table(rows: list[Row]) -> list[str]:
    """The per-density table of issue 14 (costs: ms of CPU per scan, all bases)."""
    out = [f"{'scene':<10} {'targets':>7} {'plotter':>8} {'tracker':>8} {'fusion':>8} {'x real':>7} "
           f"{'missed':>12} {'false':>12} {'switch':>7} {'breaks':>7} {'RMSE/PCRLB':>10} {'NEES':>6}",
           f"{'':<10} {'':>7} {'ms/scan':>8} {'ms/scan':>8} {'ms/scan':>8} {'':>7} "
           f"{'per scan':>12} {'per scan':>12} {'/100 tg':>7} {'/100 tg':>7} {'median':>10} {'pos':>6}"]
    for r in rows:
        total = sum(r.ms.values())
        out.append(f"{r.name:<10} {r.targets:>7} {r.ms['plotter']:>8.1f} {r.ms['tracker']:>8.1f} "
                   f"{r.ms['fusion']:>8.1f} {1e3 / total:>7.1f} "
                   f"{r.missed:>5.1f} ({100 * r.missed / r.present:4.1f}%) "
                   f"{r.false:>5.1f} ({100 * r.false / r.present:4.1f}%) {r.switches:>7.2f} "
                   f"{r.breaks:>7.2f} {r.rmse_ratio:>10.2f} {r.nees:>6.2f}")
    if len(rows) >= 2:
        n = np.log([r.targets for r in rows])
        slopes = {k: np.polyfit(n, np.log([r.ms[k] for r in rows]), 1)[0] for k in rows[0].ms}
        out.append("log-log slope of the cost per scan against targets: "
                   + ", ".join(f"{k} {v:.2f}" for k, v in slopes.items()))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", default=["dense", "dense300", "dense1000"],
                    help="names in scenarios/ or paths of .toml files")
    ap.add_argument("--scans", type=int, default=None, help="default: the whole scenario")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--profile", action="store_true", help="cProfile of the run, by cumulative time")
    args = ap.parse_args()
    rows = []
    for name in args.scenes:
        if args.profile:
            prof = cProfile.Profile()
            rows.append(prof.runcall(run, name, args.seed, args.scans))
            pstats.Stats(prof).sort_stats("tottime").print_stats(25)
        else:
            rows.append(run(name, args.seed, args.scans))
        print("\n".join(table(rows[-1:])[2:]), flush=True)
    print("\n".join(table(rows)))
    fail = [f"{r.name}: {g}" for r in rows if r.targets >= 300 for g in r.goals()]
    for f in fail:
        print(f"FAIL {f}")
    return 1 if fail else 0


if __name__ == "__main__":
    sys.exit(main())
