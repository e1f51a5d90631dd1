#!/usr/bin/env bash
# The GPU node's runs behind the dynamic studies of results/reference-h200/ (issue #45), one part a
# call, each under 9 minutes on one H100, each writing under $OUT (a run folder laid out as
# results/reference-h200/). Run from the repository root:
#
#   OUT=$OUT bash results/gpu_rerun.sh build        # first: the binaries (make -j; minutes)
#   OUT=$OUT bash results/gpu_rerun.sh accuracy     # dynamic-accuracy/: the quick study, every build
#   OUT=$OUT bash results/gpu_rerun.sh curly        # dynamic-accuracy-curly/: the same on curly hair
#   OUT=$OUT bash results/gpu_rerun.sh reduced SHARE [--resume]
#                                                   # reduced-SHARE/: one share of the reduced study (1,000 and
#                                                   # 10,000 strands, 1 s): guides (both strand counts, one timing
#                                                   # each; over 10 minutes: a stopped call leaves its timings, the
#                                                   # next one, --resume, keeps them; or in shares that
#                                                   # share no timing, a GPU each: guides-xpbd and guides-ftl,
#                                                   # or by strand count too, guides-xpbd-1k … guides-ftl-10k),
#                                                   # lra (~240 s), sag (~80 s), lod (~230 s); reduced/ is the
#                                                   # shares' CSVs joined in that order, header once
#   OUT=$OUT bash results/gpu_rerun.sh stability [SLICE ...]
#                                                   # stability/: the quick map, CPU and every CUDA build; given
#                                                   # slices, those alone, added to the map already there
#                                                   # (--add), so the map can take several calls
#   OUT=$OUT bash results/gpu_rerun.sh judge        # judge/: planted defects, honest runs, LOD scenes
#   OUT=$OUT bash results/gpu_rerun.sh gputests     # the GPU tests of the followers and LOD (no results)
#
# Copy each part's folder into results/reference-h200/ (replacing the old one; the shares of
# reduced/ joined, each CSV's header once, their calls named in results/README.md),
# then re-render the committed report:  make report REPORT_FROM=results/reference-h200 REPORT_TO=report
# (its renders' states first: harness/bench/renders.py simulate and simulate_modes on that folder).
# The other folders (sweep/, headline/, dynamic/, featurecost/, peer/, accuracy/, dynamic-curly/) are
# measured by `make bench` and the headline commands of results/README.md; none of them changed here.
set -euo pipefail
part=${1:?"usage: OUT=DIR bash results/gpu_rerun.sh build|accuracy|curly|reduced SHARE|stability [SLICE ...]|judge|gputests"}
out=${OUT:?"set OUT to the folder the runs write into"}
py="$(cat build/python 2>/dev/null || echo python3)"
mkdir -p "$out"
case "$part" in
build) make -j"$(nproc)" all planted ;;
accuracy) "$py" -m harness accuracy --model dynamic --quick --gpu auto --force \
	--out "$out/dynamic-accuracy" --report-dir "$out/report" ;;
curly) "$py" -m harness accuracy --model dynamic --scene curly --quick --analytic none --ref-max 4096 --gpu auto --force \
	--out "$out/dynamic-accuracy-curly" --report-dir "$out/report" ;;
reduced)
	share=${2:?"usage: OUT=DIR bash results/gpu_rerun.sh reduced guides|guides-SOLVER[-1k|-10k]|lra|sag|lod [--resume]"}
	case "$share" in
	guides) args=(--strands 1000 10000 --parts guides) ;;
	guides-xpbd | guides-ftl) args=(--strands 1000 10000 --parts guides --solvers "${share#guides-}") ;;
	guides-xpbd-1k | guides-ftl-1k | guides-xpbd-10k | guides-ftl-10k)
		solver=${share#guides-}
		args=(--strands "${solver#*-}" --parts guides --solvers "${solver%-*}")
		args[1]=${args[1]/k/000}
		;;
	lra) args=(--strands 1000 10000 --parts lra) ;;
	sag) args=(--strands 1000 10000 --parts sagfree sagfreq) ;;
	lod) args=(--strands 1000 10000 --parts lod) ;;
	*)
		echo "error: unknown reduced share '$share' (guides, guides-xpbd, guides-ftl, guides-xpbd-1k … guides-ftl-10k, lra, sag, lod)" >&2
		exit 2
		;;
	esac
	mkdir -p "$out/reduced-$share"
	"$py" -m harness reduced --gpu auto "${args[@]}" ${3:+"$3"} --out "$out/reduced-$share/reduced.csv" >>"$out/reduced-$share/reduced.md"
	;;
stability)
	shift
	add=()
	if [ -f "$out/stability/stability.csv" ]; then add=(--add); fi
	slices=()
	for s in "$@"; do slices+=(--slice "$s"); done
	"$py" -m harness stability --quick --gpu auto "${slices[@]}" "${add[@]}" --out "$out/stability" --report-dir "$out/report"
	;;
judge) "$py" -m harness judge --gpu auto --out "$out/judge" ;;
gputests) "$py" -m pytest tests/gpu/test_gpu_features.py tests/gpu/test_gpu_lod.py tests/native -q -ra ;;
*)
	echo "error: unknown part '$part' (build, accuracy, curly, reduced, stability, judge, gputests)" >&2
	exit 2
	;;
esac
