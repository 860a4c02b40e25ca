#!/usr/bin/env bash
# Builds the test suite with AddressSanitizer + UndefinedBehaviorSanitizer
# (gcc, -O1 -g1: line tables for stack traces, assertions on, no benchmarks,
# warnings are errors: RVLIO_WERROR)
# in ./build-asan and runs ctest there. Any finding aborts the test that
# triggered it (halt_on_error=1, -fno-sanitize-recover=all), so ctest fails.
#
#   bash scripts/sanitize.sh [--build-dir DIR] [-- extra ctest args]
#
# Suppressions for uninstrumented Debian libraries live in
# scripts/sanitizer/{asan,lsan,ubsan}.supp (narrow, each entry says why).
# Tests listed in RVLIO_SANITIZE_EXCLUDE (a ctest -E regex; default below) are
# skipped in this stage only: see the comment on the default.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
build_dir=build-asan
ctest_extra=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build-dir) build_dir=$2; shift 2 ;;
    --) shift; ctest_extra=("$@"); break ;;
    *) echo "sanitize.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
jobs=$(nproc 2>/dev/null || echo 2)

# Excluded in this stage only (the Release stage runs them all). The
# sanitizers look for memory errors and undefined behaviour in our code; the
# end-to-end suites below run the same pipeline code on longer sequences for
# accuracy, formats and workflows, 10-120 s per case under ASan, and would
# make this stage alone longer than the whole test command may take. What
# stays here: every unit and property test, every bad-input test (malformed
# bags, MCAP, db3, CDR, configurations), the fuzz regressions, the signal
# tests of run, the short end-to-end runs (RunCliNoiseFree,
# SmootherCliNoiseFree, SmootherCliShort, DeterminismTest.*), and one or two
# cases of each long suite so that each of its paths runs under the
# sanitizers: the reader thread with an error midway and an early stop, `info`
# on every storage, one divergence detection, one refine interruption, one
# compare with a failing variant, and the library's compare stopped after its
# first run (CompareLibraryTest). test_plot (PlotScriptTest) runs Python only
# and is not built here. The refine
# memory bound measures a Release build's peak (ASan's shadow memory is not
# ours); the chunk jobs' bad-input and partial-init cases stay. The report's
# browser test runs chromium, not our code, once the page is written (its data
# extraction stays here: ReportDataTest, ReportArrayTest, ...). The time-offset
# suite simulates and runs a 20 s flight in every test process (several
# minutes each under ASan); its math runs here in TimeOffsetResidual and the
# IESKF and smoother unit tests, and a scan moved by the offset in
# QuietFailureTest; its short flights (TimeOffsetShortFlights: calibrate-time
# and an estimation run on 8 s flights, 2-7 s each in Release) likewise: the
# clock check's lag search runs here in ClockCheck.*, the scan queue's stamp
# checks in ScanQueueStamps.* and the report's note and warning in
# TimeOffsetNote.*. Two of the three survey bad-input cases run a whole
# IESKF flight first; SurveyBadInput.MalformedOrMissingInitialPose stays.
# The start-check survey cases align some 20 candidate starts per run against
# a 0.6 M point survey and run a 6 s flight and a refine (a few seconds in
# Release, minutes under ASan); the alignment runs here in test_odometry.
# The worker threads of the association run here in test_common's
# ParallelFor tests and test_association (the two-thread CLI comparison is a
# minute of ASan); batch interruption in RunSignalsTest's compare case; the
# refine summaries (on by default) in every other Refine case (their
# agreement with the exact factors is math, checked in Release). The LAS
# readers' test runs Node.js on files our code wrote (the writer's bytes are
# checked here by LasWriter.*); the LAS memory bounds measure a Release
# build's peak, as the refine one does; MapLasCli runs run, refine and merge
# end to end for the one call each makes to the LAS writer, which runs here in
# LasExport.* and LasWriter.*. The survey ties' end-to-end cases (ControlCli:
# a 50 s stop-and-go flight run and refined twice; a 40 s flight through both
# portals refined twice) run refine for a minute or more under ASan; their
# math runs here in PositionFactor, FitYawTranslation, RestPeriods,
# SurveyTies and ControlFile, and the bad control files in ControlCli's
# bad-input case. The
# survey-coordinates suite (SurveyCoordinates) runs a flight twice, a refine
# and eval --map of a 590 k point survey; the local frame it checks runs here
# in LocalOrigin, VoxelMap, ReferenceMap, MapMetrics and ReferenceMapFileTest. Live runs `rvlio live` against rosmaster,
# rosbag and DDS in real time (about a minute of wall time whatever the
# build); its queues, ordering and errors run here in LiveSensorSource.*,
# the propagator in ImuPropagator.*, the output messages in CdrTest.*.
# ImuTrajectoryCli runs both backends, two refine chunks and three merges on
# a 6 s flight for trajectory_imu.tum (9 s in Release); its interpolation
# runs here in ImuRateTrajectory.*, the chunk blend in RefineJobs.*.
# RVLIO_SANITIZE_EXCLUDE='^$' runs everything.
ex=(
  RvCliTest.TunnelRvOnBeatsRvOffOnAteAndAlongAxisError
  RvCliTest.HallStaysInactiveAndKeepsItsAccuracy
  RefineCliTest.RefineFromAnIeskfRunLowersItsAteAndWritesTheOutputs
  RunCliTest.IeskfWritesTheOutputContractAndMeetsTheRegressionBound
  SmootherCliTest.WritesTheOutputContractWithinTheAccuracyBound
  SmootherCliTest.AnImuGapInsideTheWindowIsBridged
  CompareTest.FullCompareWritesTablesEqualToEvalAndPlots
  CompareTest.EveryVariantFailedIsExitOne
  CompareTest.RefMapAddsMapColumnsInTheGroundTruthFrame
  DemoTest.ShortDemoSimulatesComparesAndWritesTheReport
  CompareLibraryTest.TypedRowsInMemoryEqualTheRunFilesAndTheCallbackComesOncePerRun
  'AblateRunTest\..*' 'ExtrinsicCliTest\..*' 'ExtrinsicCliSway\..*'
  'PresetsAndBackends/TimeOffsetMatrix\..*'
  DivergenceCli.UpsideDownLidarIsCaughtOnAShortFlight
  DivergenceCli.AccelerometerReportsGButConfigSaysMetresPerSecondSquared
  DivergenceCli.AccelerometerUnitGGivenForMetresPerSecondSquaredData
  DivergenceCli.LidarTopicOfAnotherRobot
  DivergenceCli.OnlineExtrinsicEstimationWithExactExtrinsicsStaysHealthy
  DivergenceCli.AllowDivergenceExitsZeroButStillReports
  DivergenceCli.MonitorCanBeSwitchedOff
  DivergenceCli.SmootherIsMonitoredToo
  DivergenceCli.CompareMarksDivergedRows
  DivergenceCli.AblateMarksDivergedCells
  DivergenceCli.NeverFiresOnTheNormalPresets
  InputStreamTest.LivoxCustomMsgGivesThePointCloud2Trajectory
  InputStreamTest.TimeOffsetUndoesAnInjectedLidarDelay
  InputStreamTest.StartAndDurationSelectTheScansOfTheWindow
  InputStreamTest.ReaderThreadOutputsAreByteIdentical
  InputStreamTest.StreamAppliesTheTimeOffsetToEveryScanTime
  FormatsTest.RunGivesByteIdenticalOutputsOnEveryFormat
  FormatsTest.LivoxCustomMsgRunsAreByteIdenticalAcrossRos1McapAndDb3
  FormatsTest.SplitBagFolderReadsAsTheWholeRecording
  RefineSignalsTest.ResumeAfterFewerRoundsEqualsTheUninterruptedResult
  RefineSignalsTest.KilledAfterARoundThenResumedEqualsTheUninterruptedResult
  RefineMemory.PeakPerScanOfA400ScanRefineStaysBounded
  RefineChunksCliTest.MergedChunksAgreeWithTheWholeRefineHaveNoBorderStepsAndRefuseBadSets
  'ReportBrowserTest\..*'
  'Backends/SurveyStart\..*' SurveyCli.InitialPoseFromATumFileAndRefineHeldToTheMap
  SurveyBadInput.MissingEmptyTruncatedOrNonFiniteMap SurveyBadInput.MapInMillimetresOrFarFromTheStart
  'TimeOffsetCliTest\..*' 'TimeOffsetShortFlights\..*'
  'DegeneracyCliTest\..*'
  'SurveyFlights\..*' SurveyFeatureless.StartTwentyMetresOffAlongTheAxisIsRefused
  'SurveyCoordinates\..*' 'SurveyStartCheck\..*'
  AssociationThreadsCliTest.TwoThreadsWriteTheSameOutputsAsOne
  BatchSignalsTest.InterruptedAblationKeepsFinishedCellsAndResumes
  Refine.SummarizedFactorsAgreeWithExactFactors
  'LasReaders\..*' LasWriter.MemoryStaysBoundedWhileMillionsOfPointsAreWritten
  LasExport.AMapOfMillionsOfPointsIsExportedInBoundedMemory MapLasCli.RunRefineAndMergeWriteMapLasWhenAsked
  Live
  ControlCli.RunThenRefineWithMarksOrWallTargetsDeliversInTheSurveyFrame
  ControlCli.GnssAtBothPortalsWithAndWithoutControlPointsInside
  ImuTrajectoryCli.RunRefineAndMergeWriteTheImuRateTrajectoryOnlyWhenAsked
)
default_exclude="^($(IFS='|'; echo "${ex[*]}"))\$"
exclude=${RVLIO_SANITIZE_EXCLUDE:-$default_exclude}

cmake -S . -B "$build_dir" -DRVLIO_SANITIZE=ON -DRVLIO_BUILD_BENCH=OFF -DRVLIO_WERROR=ON -DRVLIO_UNITY_BUILD=all \
  -DCMAKE_C_COMPILER=gcc -DCMAKE_CXX_COMPILER=g++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1" >/dev/null
cmake --build "$build_dir" -j "$jobs"

supp="$root/scripts/sanitizer"
export ASAN_OPTIONS="halt_on_error=1:abort_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1:suppressions=$supp/asan.supp"
export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="halt_on_error=1:abort_on_error=1:print_stacktrace=1:suppressions=$supp/ubsan.supp"

# The end-to-end fixtures' simulations (CachedSimulate, test/cli/cli_util.h)
# come from the Release stage's tool and its cache when build/bin/rvlio
# exists (the test command builds it first): the tool under test still runs
# sanitized on every command; only the preparation of its input, the same
# files either way, skips an ASan simulation per suite. The simulator runs
# sanitized in test_sim and wherever a test calls `simulate` itself.
# RVLIO_TEST_SIM_BIN= (empty) simulates with the sanitized tool.
if [[ -z "${RVLIO_TEST_SIM_BIN+x}" && -x "$root/build/bin/rvlio" ]]; then
  export RVLIO_TEST_SIM_BIN="$root/build/bin/rvlio"
  export RVLIO_TEST_CACHE="${RVLIO_TEST_CACHE:-$root/build/test-sim-cache}"
fi

cd "$build_dir"
args=(--output-on-failure -j "$jobs")
[[ -n "$exclude" ]] && args+=(-E "$exclude")
ctest "${args[@]}" "${ctest_extra[@]}"
