"""The entries of the data dictionary (:mod:`ligwf.report.dictionary`): every column ligwf
writes, once, with its SI unit, a short label and its meaning.

A column shared by several tables (``case_id``, ``cg``, ``d50``) has one entry in
:data:`COMMON`; a name that means something else in one table has an entry in that
table's :data:`OVERRIDES`. Interval, floor, pooling and ratio columns (``x_lo``,
``x_floor``, ``x_mean``, ``twin_x``) are derived from their base entry by the suffix
rules of :mod:`ligwf.report.dictionary`. Units: ``1`` a ratio, share or fraction;
``count`` a whole number; ``text``; ``flag`` true / false; ``step`` an engine time step
number. ``show``: the unit the report displays (``mm`` for a diameter in m).
"""

from __future__ import annotations

from ligwf.study import layout

#: (name, unit, label, meaning[, shown unit]) of the columns shared by the tables
COMMON: tuple[tuple[str, ...], ...] = (
    # identity
    ("case_id", "text", "case", "case folder name (a case: one scene at one CG level, rule "
     "and replica; its engine execution is a run): cg<level>-<rule>-r<replica>[_<swept "
     "values>][_<control>]"),
    ("group", "text", "group", "sweep group: the swept scene values as canonical JSON ({}: "
     "no scene value swept; a control twin has its own group); readable in the report as "
     "`all cases`, `key=value`, `cohesionless control`"),
    ("group_label", "text", "group", "the sweep group as the report names it: `all cases`, "
     "the swept values as key=value, `cohesionless control` for the twins"),
    ("cg", "1", "CG", "coarse-graining level n (particles n times the original diameter; 1: "
     "the original, the reference)"),
    ("rule", "text", "rule", "CG scaling rule of the bridge forces: none (CG1), weber, bond"),
    ("replica", "count", "rep", "replica number: which of its condition's cases this is "
     "(replicas differ only by their insertion seeds)"),
    ("replicas", "count", "replicas", "replicas (cases of the condition) pooled in this row"),
    ("condition", "text", "condition", "a condition: cg<level>[-<rule>] [group] (sweep group, "
     "CG level and rule; replicas pooled)"),
    ("reference", "text", "reference", "the CG1 condition this row is compared with (empty: "
     "a CG1 row or no CG1 in the group)"),
    ("step", "step", "step", "engine time step of the frame"),
    ("time", "s", "time", "simulated time of the frame from the start of the run (fill and "
     "settle included)"),
    ("frames", "count", "frames", "frames used"),
    ("status", "text", "status", "ok, or why the frame was not used"),
    ("reason", "text", "reason", "why (empty when used)"),
    # run facts and costs
    ("particles", "count", "particles", "particles in the run (CG-n: about 1/n^3 of the "
     "original)"),
    ("original_particles", "count", "orig. particles", "particles of the original (CG1) "
     "system the case stands for"),
    ("dt", "s", "dt", "engine time step"),
    ("steps", "count", "steps", "time steps run"),
    ("simulated_seconds", "s", "simulated", "simulated time run (fill, settle, production)"),
    ("production_seconds", "s", "production", "simulated production time (drum rotating)"),
    ("wall_seconds", "s", "wall", "wall-clock time of the run"),
    ("core_seconds", "core-s", "cores x wall", "cores x wall time of the run"),
    ("fill_core_seconds", "core-s", "fill", "core-seconds of the fill phase"),
    ("settle_core_seconds", "core-s", "settle", "core-seconds of the settle phase"),
    ("production_core_seconds", "core-s", "production",
     "core-seconds of the production phase"),
    ("production_core_rate", "core-s/s", "production cost",
     "production core-seconds per simulated second of production"),
    ("production_core_rate_k", "core-s/s", "production cost per 1k orig. particles",
     "production core-seconds per simulated second per 1,000 particles of the original "
     "system (slices and CG levels on one footing)"),
    ("production_wall_rate", "s/s", "production wall per sim. s",
     "production wall seconds per simulated second of production"),
    ("nprocs", "count", "ranks", "MPI ranks the case ran on"),
    ("speedup_core", "1", "speedup", "CG1 production core-s per simulated second per original "
     "particle over this case's (CG1 mean of the group); in the verdict of a sweep without "
     "CG1, the planner's CG1 core-s per simulated second over the level's"),
    ("speedup_wall", "1", "speedup (wall)", "as speedup_core with wall time"),
    # flow
    ("steady_fraction", "1", "steady from", "share of production left out as start-up before "
     "the steady window"),
    ("steady_from_step", "step", "steady from step", "first step of the steady window"),
    ("com_angle_mean", "deg", "COM angle", "angle of the bed's centre of mass from the vertical, "
     "mean over the steady window"),
    ("com_angle_std", "deg", "COM angle std", "its standard deviation over the steady frames"),
    ("rigid_fraction_mean", "1", "rigid share", "mean share of the bed moving rigidly with the "
     "drum"),
    ("rms_speed_mean", "m/s", "rms speed", "root-mean-square particle speed, mean over the "
     "steady window"),
    ("kinetic_energy_mean", "J", "kinetic energy", "kinetic energy of the bed, mean over the "
     "steady window"),
    ("flowing_layer_speed_mean", "m/s", "flowing-layer speed", "mean speed in the flowing layer"),
    # granules
    ("contacts", "count", "contacts", "particle-particle contacts and bridges in the contact "
     "dump"),
    ("bonds", "count", "bonds", "liquid bonds passing the study's bond criterion"),
    ("granules", "count", "granules", "granules of at least min_particles members"),
    ("largest_fraction", "1", "largest cluster", "share of the bed in the largest granule"),
    ("largest_percolates", "flag", "largest percolates", "the largest granule closes a cycle "
     "around the periodic axis (bed-spanning)"),
    ("largest_granule", "1", "largest granule", "share of the bed in the largest counted "
     "(non-percolating) granule"),
    ("granule_share", "1", "bed in granules", "share of the bed's solid volume in counted "
     "granules"),
    ("percolating_share", "1", "bed percolating", "share of the bed in percolating "
     "(bed-spanning) granules, left out of the GSD"),
    ("percolating_frames", "1", "percolating frames", "share of the steady frames holding a "
     "percolating granule (controls: under the row's definition)"),
    ("percolating", "flag", "percolating", "the granule closes a cycle around the periodic axis "
     "(a flag of one granule; shares are percolating_share and percolating_frames)"),
    ("d10", "m", "d10", "10 % of the granule volume is in granules up to this equivalent-sphere "
     "diameter (volume-weighted GSD)", "mm"),
    ("d50", "m", "d50", "median equivalent-sphere diameter of the volume-weighted GSD", "mm"),
    ("d90", "m", "d90", "90 % diameter of the volume-weighted GSD", "mm"),
    # GSD comparison (ligwf.analysis.records.gsd)
    ("error_band", "1", "error band", "relative per-bin error of CG-n against CG1 that locates "
     "the size limits (analysis.error_band)"),
    ("min_particles", "count", "min particles", "smallest granule counted in the GSD "
     "(analysis.min_particles)"),
    ("lower_limit", "m^3", "GSD lower limit", "smallest granule volume from which on every bin "
     "holding >= 1 % of the CG1 granule volume is within the error band (CG-n good ABOVE it; "
     "nan: none located, CG-n never enters the band)"),
    ("upper_limit", "m^3", "GSD upper limit", "largest granule volume up to which every bin "
     "holding >= 1 % of the CG1 volume is within the error band (the source study's limit; "
     "CG-n good BELOW it; nan: the smallest bin is already outside)"),
    ("error_below_lower", "1", "GSD err below lower limit", "relative L1 error of the "
     "volume-weighted GSD against CG1 over the bins below the lower limit (the side CG-n does "
     "not resolve; no limit located: every bin, = error_all)"),
    ("error_above_lower", "1", "GSD err above lower limit", "relative L1 error over the bins "
     "above the lower limit (nan when no limit is located)"),
    ("error_below_upper", "1", "GSD err below upper limit", "relative L1 error over the bins "
     "below the upper limit (nan when no upper limit is located)"),
    ("error_above_upper", "1", "GSD err above upper limit", "relative L1 error over the bins "
     "above the upper limit (no upper limit located: every bin)"),
    ("error_all", "1", "GSD err all bins", "relative L1 error of the volume-weighted GSD "
     "against CG1 over all bins, no size limit: sum |GSD_n - GSD_1| / sum GSD_1"),
    ("gsd_lower_limit", "m^3", "GSD lower limit", f"lower_limit of {layout.GSD_SUMMARY_TABLE} (granule "
     "volume; nan: none located)"),
    ("gsd_lower_limit_diameter", "m", "GSD lower limit d", "equivalent-sphere diameter of the "
     "GSD lower limit volume (nan: none located, every bin below it)", "mm"),
    ("gsd_error_below_lower", "1", "GSD err below lower limit", "error_below_lower of "
     f"{layout.GSD_SUMMARY_TABLE} (no limit located: every bin, = GSD err all bins)"),
    ("gsd_error_above_lower", "1", "GSD err above lower limit", "error_above_lower of "
     f"{layout.GSD_SUMMARY_TABLE} (nan when no lower limit is located)"),
    ("gsd_error_all", "1", "GSD err all bins", f"error_all of {layout.GSD_SUMMARY_TABLE}: the whole GSD's "
     "relative L1 error against CG1"),
    # flow fields (ligwf.inference.field_errors)
    ("field_error", "1", "layer velocity err", "the field criterion (what the verdict's "
     "continuum-fields budget reads): the in-plane velocity in the drum frame, U - omega x "
     "r, inside the flowing layer (CG1 nodes with solid fraction >= 0.1 moving relative to "
     "the drum at >= 0.2 omega R), phi_1-weighted RMS of the difference of the mean "
     "fields over omega R, less the noise of both arms' run scatter (condition table; a "
     "case's value: its raw distance to its group's CG1 mean); _lo/_hi: bounds that each "
     "hold with >= 95 %; _floor: the same criterion CG1 against CG1; _se: not given; at "
     "the kernel width field_error_kernel"),
    ("field_error_kernel", "1", "verdict field kernel", "the kernel width of field_error "
     "(analysis.field_kernel), CG1 mean diameters"),
    ("field_error_k1", "1", "layer velocity err k1", "field_error at a kernel width of 1 CG1 "
     "mean diameter"),
    ("field_error_k2", "1", "layer velocity err k2", "field_error at a kernel width of 2 CG1 "
     "mean diameters"),
    ("field_error_k4", "1", "layer velocity err k4", "field_error at a kernel width of 4 CG1 "
     "mean diameters"),
    ("field_error_distance", "1", "layer velocity raw distance", "the field criterion's raw "
     "distance between the arms' mean fields (before the noise is taken off), omega R; its "
     "bounds lie this +- t sqrt(run_var / runs + ref_var / ref_runs)"),
    ("field_error_run_var", "1", "layer velocity CG-n run noise", "the field criterion's "
     "per-run noise of the CG-n arm: sum over the layer's nodes of w x the runs' variance, "
     "(omega R)^2 (what more CG-n replicas would shrink; nan with one run)"),
    ("field_error_ref_var", "1", "layer velocity CG1 run noise", "the same for the CG1 arm"),
    ("field_error_runs", "count", "layer velocity CG-n runs", "CG-n runs in the field "
     "criterion"),
    ("field_error_ref_runs", "count", "layer velocity CG1 runs", "CG1 runs in the field "
     "criterion"),
    ("field_solid_error", "1", "solid fraction field err (L1)", "relative L1 error of the "
     "solid-fraction field over the cross-section against CG1: sum |phi_n - phi_1| / sum "
     "phi_1"),
    ("comparison", "text", "comparison", "CG1 vs CG1 (two halves of the CG1 runs: the "
     "criterion should find nothing) or cohesionless twin vs wet CG1"),
    ("control", "text", "compared group", "the sweep group of the compared runs (the "
     "cohesionless twins', or the CG1 group itself)"),
    ("split", "text", "split", "how the two arms were formed (replicas against replicas, or "
     "the first against the second half of every run's window)"),
    ("runs", "count", "runs", "runs (or half windows) of the compared arm"),
    ("ref_runs", "count", "reference runs", "runs (or half windows) of the reference arm"),
    # controls (ligwf.analysis.granules.control_run)
    ("twin_id", "text", "twin", "the cohesionless twin of the case (surface tension and "
     "viscosity / 1000, same seeds)"),
    ("definition", "text", "definition", "granule definition (study's, or a variant)"),
    ("passes", "flag", "passes", "the definition meets every pre-registered control criterion"),
    ("verdict", "text", "verdict", "the control verdict in one sentence"),
    ("share_2", "1", "bed in granules >= 2", "share of the bed in granules of >= 2 particles"),
    ("share_10", "1", "bed in granules >= 10", "share of the bed in granules of >= 10 particles"),
    ("count_10", "count", "granules >= 10", "granules of >= 10 particles per frame"),
    ("d50_mm", "mm", "d50", "median equivalent diameter of granules of >= 10 particles"),
    ("largest_share", "1", "largest share", "share of the bed in the largest granule"),
    ("persist_short", "1", "persistence short", "share of member pairs still together after "
     "the short interval"),
    ("persist_quarter", "1", "persistence T/4", "share of member pairs still together after a "
     "quarter revolution"),
    ("comove_ratio", "1", "co-movement", "separation rate of member pairs over that of "
     "non-member pairs (< 1: members move together)"),
    ("ari_seed", "1", "ARI seed", "adjusted Rand index of the granules across optimiser seeds"),
    ("ari_order", "1", "ARI order", "adjusted Rand index across contact orders"),
    # sensitivity (ligwf.analysis.granules.definitions.variants)
    ("variant", "text", "variant", "the definition's setting moved x0.8 / x1.25 (first: as set)"),
    ("method", "text", "method", "analysis.granules of the variant"),
    ("velocity_frame", "text", "velocity frame", "analysis.velocity_frame of the variant"),
    ("resolution", "1", "resolution", "analysis.resolution (the CPM resolution) of the variant"),
    ("max_velocity_angle", "deg", "max velocity angle", "analysis.max_velocity_angle of the "
     "variant"),
    ("min_relative_force", "1", "min relative force", "analysis.min_relative_force of the "
     "variant"),
    ("hold_time", "s", "hold time", "analysis.hold_time of the variant"),
    # pooling
    ("k", "count", "K", "CG-n replicas pooled"),
    ("pool", "count", "pool", "pool number (disjoint pools of K replicas, in replica order)"),
    ("pools", "count", "pools", "disjoint pools of K replicas"),
    ("frames_per_pool", "count", "frames / pool", "mean frames per pool"),
    # noise floor
    ("metric", "text", "metric", "the metric (a column of the case and condition tables)"),
    ("cg1_value", "metric", "CG1 value", "the metric over the group's CG1 runs (its unit)"),
    ("cg1_scatter", "metric", "CG1 scatter", "CG1-vs-CG1 scatter of the metric (other seeds; "
     "one run: its within-run error, indicative)"),
    ("source", "text", "from", "what the scatter was estimated from"),
)

#: the verdict's columns (ligwf.inference.verdict_records: one row per criterion)
VERDICT = (
    ("condition_state", "text", "condition verdict", "meets (every assessed criterion "
     "passes), fails (one fails) or undecided"),
    ("criterion", "text", "criterion", "the accept: key of the criterion (the verdict "
     "criteria, listed from their registry at the end of this page)"),
    ("label", "text", "criterion label", "the criterion as the report names it"),
    ("unit", "text", "unit", "unit of value, lo, hi and budget (empty: a ratio)"),
    ("state", "text", "verdict", "pass (signed criteria: the (1 - 2 alpha) interval of "
     "CG-n - CG1 inside +-budget, two one-sided tests; norms: the upper bound within the "
     "budget), fail (its fail test rejects, surviving Holm over the level's tested "
     "criteria), undecided, or not assessed (with a note); alpha, the degrees-of-freedom "
     "rule and the family rule: the verdict record's statistics"),
    ("value", "unit", "value", "the criterion's measured value (in the row's unit): the "
     "signed difference CG-n - CG1, or the noise-corrected distance"),
    ("lo", "unit", "lo", "lower bound of its interval (signed criteria: the (1 - 2 alpha) "
     "interval, alpha in the verdict record's statistics)"),
    ("hi", "unit", "hi", "upper bound of its interval"),
    ("budget", "unit", "budget", "the tolerance it is held to: its accept: value (its share "
     "of the error budget; a sequential study's cost limit is the core-hour cap, not a "
     "budget)"),
    ("shown_within", "unit", "shown within", "the largest |error| its interval allows (a "
     "one-sided (1 - alpha) bound): the error this level is shown to stay within"),
    ("budget_source", "text", "budget from", "where the criterion's error budget came from "
     "(the accept: block)"),
    ("decide_by", "text", "decide by", "undecided only: the cheapest way to decide it "
     "(extend: more production on the existing runs, continued from their restarts; "
     "replicas: more replicas, new cases of the arm), from the arms' variance components "
     "(ligwf.inference.sampling)"),
    ("decide_arm", "text", "decide on", "the arm(s) to extend or add to: CG-n, CG1 or both"),
    ("decide_amount", "1", "decide amount", "extend: simulated seconds of production more "
     "per run; replicas: CG-n replicas to add"),
    ("decide_amount_cg1", "count", "decide CG1 replicas", "replicas: CG1 replicas to add"),
    ("decide_core_hours", "core-h", "decide cost", "core-hours of that option on one rank "
     "per run, from the planner's measured rates (ligwf.engine.plan)"),
    ("decide_half_width", "unit", "predicted half-width", "the half-width of the interval "
     "predicted after it, the difference and variances as measured (a plan)"),
    ("note", "text", "note", "why a criterion was not assessed, or what decides it"),
    ("too_short", "flag", "runs too short", "the steady window of a run of either arm of "
     "this condition starts at its cap: the runs are too short to show a steady state"),
    ("too_short_note", "text", "too short: fix", "which runs are too short and what would "
     "fix it (the production each needs, the planner's rule; empty when none is)"),
    ("cheapest", "flag", "cheapest", "this condition is the cheapest of its group that meets "
     "the whole budget"),
)

#: placed liquid's spreading per CG-n level (ligwf.inference.spreading)
SPREADING = (
    ("runs", "count", "runs", "runs of the CG-n level"),
    ("censored_runs", "count", "not reached", "runs whose dry particles never held the "
     "registered share of the liquid (their time is a lower bound)"),
    ("t_spread_rev_geomean", "rev", "spreading time", "geometric mean over the level's runs "
     "of the revolutions until the particles dry at the first frame hold 0.25 of their "
     "uniform share of the liquid (ligwf.analysis.flow.spreading)"),
    ("cg1_runs", "count", "CG1 runs", "CG1 runs of the sweep group"),
    ("t_spread_rev_cg1", "rev", "CG1 spreading time", "the same over the CG1 runs"),
    ("rate_ratio", "1", "rate ratio", "CG1 spreading time over the level's: how many times "
     "faster the liquid spreads in physical space at CG-n"),
    ("rate_ratio_low", "1", "lo", "lower bound of its 95 % interval (Welch's t on log times; "
     "coverage not measured on data like these)"),
    ("rate_ratio_high", "1", "hi", "upper bound of its 95 % interval"),
    ("df", "1", "df", "Welch degrees of freedom of the log-time difference"),
    ("exponent", "1", "exponent k", "log(rate ratio) / log(n): 2 for the n^2 a walk over "
     "contacts with n times longer steps predicts"),
    ("exponent_low", "1", "k lo", "the interval's lower bound mapped through log(n)"),
    ("exponent_high", "1", "k hi", "the interval's upper bound mapped through log(n)"),
    ("expected_ratio", "1", "n^2", "the expected rate ratio, n^2"),
    ("contains_expected", "flag", "n^2 inside", "the interval contains n^2"),
    ("above_one", "flag", "faster", "the interval lies above 1: shown faster than CG1"),
    ("is_bound", "flag", "bound", "a run never reached the share: the ratio is a bound"),
    ("cg1_spread", "1", "CG1 replicas' ratio", "the largest ratio of two CG1 replicas' "
     "spreading times (the null: CG1 against CG1)"),
)

#: table file -> (name, unit, label, meaning[, shown]) that differ there from COMMON
#: the extrapolated CG1 reference's columns (ligwf.inference.reference)
EXTRAPOLATION = (
    ("column", "text", "metric", "the case-table column extrapolated (a signed criterion's)"),
    ("levels", "text", "CG levels", "the CG-n levels of the rule the line was fitted on"),
    ("replicas", "text", "runs a level", "replicas (one run each) at each of those levels, in "
     "their order"),
    ("extrapolated", "metric", "extrapolated CG1", "the line through the level means at n = 1 "
     "(weber - bond rows: the two rules' difference)"),
    ("lo", "metric", "lo", "lower bound of its 95 % interval (noise and model term)"),
    ("hi", "metric", "hi", "upper bound of its 95 % interval"),
    ("half_width", "metric", "half-width", "half the interval's width"),
    ("noise_se", "metric", "noise se", "standard error from the levels' run-to-run noise"),
    ("model_term", "metric", "model term", "standard uncertainty of the line's bias under the "
     "curvature prior (ligwf.inference.extrapolation.CURVATURE_PRIOR)"),
    ("df", "1", "df", "effective degrees of freedom of noise and model term"),
    ("form", "text", "form", "checked (three or more levels, no lack of fit), unchecked (two "
     "levels) or rejected (the rule does not extrapolate)"),
    ("lack_of_fit_p", "1", "lack of fit p", "p of the test that the level means lie on a line"),
    ("observed_order", "1", "observed order", "p of theta_1 + b (n - 1)^p through three "
     "levels (printed, not a gate)"),
    ("slope_per_level", "metric", "slope", "the fitted change per CG level"),
    ("cg1_measured", "metric", "measured CG1", "the mean of the group's CG1 runs, if any"),
    ("cg1_se", "metric", "CG1 se", "its standard error"),
    ("cg1_replicas", "count", "CG1 runs", "CG1 replicas of the group (one run each)"),
    ("cg1_inside", "flag", "inside", "the measured CG1 mean lies in the 95 % interval"),
)

OVERRIDES: dict[str, tuple[tuple[str, ...], ...]] = {
    layout.GSD_TABLE: (
        ("frames", "count", "frames", "frames pooled over the condition's replicas"),
        ("bin", "count", "bin", "volume bin (logarithmic, decade-aligned)"),
        ("v_lo", "m^3", "bin from", "lower edge of the bin (granule volume)"),
        ("v_hi", "m^3", "bin to", "upper edge of the bin"),
        ("v_mid", "m^3", "bin centre", "geometric centre of the bin"),
        ("number_fraction", "1", "number fraction", "share of the granules in the bin"),
        ("number_lo", "1", "number fraction lo", "lower 95 % bootstrap bound of the number "
         "fraction"),
        ("number_hi", "1", "number fraction hi", "upper 95 % bootstrap bound"),
        ("volume_fraction", "1", "volume fraction", "share of the granule volume in the bin"),
        ("volume_lo", "1", "volume fraction lo", "lower 95 % bootstrap bound of the volume "
         "fraction"),
        ("volume_hi", "1", "volume fraction hi", "upper 95 % bootstrap bound"),
        ("ref_volume_fraction", "1", "CG1 volume fraction", "the CG1 reference's volume "
         "fraction in the bin"),
        ("rel_error", "1", "relative error", "(CG-n - CG1) / CG1 volume fraction of the bin"),
        ("below_lower_limit", "flag", "below lower limit", "the bin's centre is below the GSD "
         "lower limit (every bin when none is located)"),
    ),
    layout.GRANULES_TABLE: (
        ("frame", "count", "frame", "frame number of the case"),
        ("granule", "count", "granule", "granule id in the frame"),
        ("members", "count", "members", "particles in the granule"),
        ("volume", "m^3", "volume", "physical solid volume of the granule"),
        ("primary_volume", "m^3", "primary volume", "volume / n^3 (the source study's estimate "
         "of the original granule)"),
        ("com_x", "m", "COM x", "centre of mass, x (periodic axis unwrapped)"),
        ("com_y", "m", "COM y", "centre of mass, y"),
        ("com_z", "m", "COM z", "centre of mass, z"),
        ("first_id", "count", "first id", "smallest particle id of the granule (a stable tag)"),
    ),
    layout.FRAMES_TABLE: (
        ("particles", "count", "particles", "particles in the frame"),
        ("granules", "count", "granules", "granules (connected sets of bonds) in the frame"),
    ),
    layout.KINETICS_TABLE: (
        ("time", "s", "time", "simulated time of the frame from the start of the run"),
    ),
    layout.KINETICS_SUMMARY_TABLE: (
        ("time", "s", "time", "simulated time from the start of the run (frames of the "
         "condition's replicas at this time)"),
    ),
    layout.SENSITIVITY_TABLE: (
        ("granules", "count", "granules", "counted granules per frame under the variant"),
        ("frames", "count", "frames", "steady frames re-analysed"),
        ("d50_ratio", "1", "d50 / as set", "d50 over that of the definition as set (first "
         "row)"),
    ),
    layout.FLOW_TABLE: (
        ("frames", "count", "frames", "checked production frames of the steady window"),
    ),
    layout.VERDICT_TABLE: VERDICT,
    layout.EXTRAPOLATION_REPORT: EXTRAPOLATION,
    layout.SPREADING_REPORT: SPREADING,
}
