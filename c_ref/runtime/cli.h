/* cli.h — command-line parsing shared by hairsim-cpu and hairsim-cuda (docs/interfaces.md). */
#ifndef HB_CLI_H
#define HB_CLI_H

#include <stdint.h>
#include <stdio.h>

#include "runtime/params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Fills o from argv. Returns 0 to run, 1 when --help/--version was printed (exit 0), or
 * −1 with one line in err. `backend` is "cpu" or "cuda" (some flags belong to one). */
int hb_parse_args(int argc, char **argv, const char *backend, hb_options *o, char *err, size_t errlen);
void hb_print_usage(FILE *f, const char *prog, const char *backend);
void hb_default_options(hb_options *o);

/* Limits the binaries check that the harness reads through --limits (docs/interfaces.md,
 * "Command line"); the flag table's ranges (--block-size, --threads, ...) are printed from the table. */
#define HB_COUNT_MAX 1000000   /* --substeps and --iterations at most */
#define HB_SUBSTEP_MIN_S 1e-12 /* h = --frame-dt / --substeps, s */
#define HB_SUBSTEP_MAX_S 1e3
#define HB_GRID_N_MIN 2 /* --grid nodes per axis */
#define HB_GRID_N_MAX 512
#define HB_GRID_POINTS_MAX (UINT64_C(1) << 31) /* --strands x --points with --grid */
#define HB_COLLIDER_SWEEPS_MAX 8               /* --collider-sweeps at most (docs/model.md §3.17) */
#define HB_BLOCK_MULTIPLE 32                   /* --block-size: a whole number of warps */
/* Prints the limits as one JSON object (--limits). */
void hb_print_limits(FILE *f, const char *backend);

/* The dynamic flags' table: bit i of hb_options.dyn_given is entry i; the run-shape flags
 * (--frames, --output-every, --velocities, --draw, --draw-image) set HB_DYN_GIVEN_RUN. */
#define HB_DYN_GIVEN_RUN (1ull << 63)
const char *hb_dyn_flag_name(int i);
int hb_dyn_flag_index(const char *flag);
/* Whether the field of flag i differs between a and b. */
int hb_dyn_flag_differs(int i, const hb_dynamics *a, const hb_dynamics *b);
/* A number in the command line's grammar (docs/interfaces.md, "Numbers"): 0, or −1 with one
 * line naming `what` in err. */
int hb_parse_number(const char *what, const char *v, double *out, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
int hb_stage_list_has_empty_item(const char *v);

#endif
