/* record.c — the run record as JSON (docs/interfaces.md) and as a short summary. */
#include "app/record.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef HB_GIT_REV
#define HB_GIT_REV "unknown"
#endif

const char *hb_git_revision(void)
{
    return HB_GIT_REV;
}

const char *hb_compiler(void)
{
#if defined(__clang__)
    return "clang " __clang_version__;
#elif defined(__GNUC__)
    return "gcc " __VERSION__;
#else
    return "unknown";
#endif
}

void hb_cpu_model(char *out, size_t n)
{
    snprintf(out, n, "unknown CPU");
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (!f) return;
    char line[512];
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, "model name", 10) == 0) {
            char *c = strchr(line, ':');
            if (c) {
                c++;
                while (*c == ' ') c++;
                c[strcspn(c, "\n")] = '\0';
                snprintf(out, n, "%s", c);
            }
            break;
        }
    }
    fclose(f);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void hb_time_stats(const double *t, int n, double *median, double *min, double *max)
{
    if (n <= 0) {
        *median = *min = *max = 0.0;
        return;
    }
    double *s = malloc((size_t)n * sizeof *s);
    if (!s) {
        *median = *min = *max = NAN;
        return;
    }
    memcpy(s, t, (size_t)n * sizeof *s);
    qsort(s, (size_t)n, sizeof *s, cmp_double);
    *min = s[0];
    *max = s[n - 1];
    *median = n % 2 ? s[n / 2] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
    free(s);
}

static void json_str(FILE *f, const char *s)
{
    if (!s) {
        fputs("null", f);
        return;
    }
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
        else if (*p < 0x20) fprintf(f, "\\u%04x", *p);
        else fputc(*p, f);
    }
    fputc('"', f);
}

static void json_num(FILE *f, double v)
{
    if (isfinite(v)) fprintf(f, "%.17g", v);
    else fputs("null", f);
}

/* `, "key": value` */
static void json_key_num(FILE *f, const char *key, double v);
static void json_key_str(FILE *f, const char *key, const char *v);

/* the simulate entry's "draw" (docs/interfaces.md "Drawing on the GPU"), null without --draw */
static void json_draw(FILE *f, const hb_stage_record *st)
{
    if (!st->drawn) {
        fputs(", \"draw\": null", f);
        return;
    }
    const hb_draw_result *d = &st->draw;
    fprintf(f, ", \"draw\": {\"width\": %d, \"height\": %d, \"frames\": %d", d->width, d->height, d->frames);
    json_key_num(f, "simulate_ms", d->simulate_ms);
    json_key_num(f, "compute_ms", d->compute_ms);
    json_key_num(f, "compute_frame_ms", d->compute_frame_ms);
    json_key_num(f, "gl_write_ms", d->gl_write_ms);
    json_key_num(f, "gl_ms", d->gl_ms);
    json_key_num(f, "gl_frame_ms", d->gl_frame_ms);
    if (d->gl[0]) json_key_str(f, "gl", d->gl);
    else fputs(", \"gl\": null", f);
    if (d->gl_missing[0]) json_key_str(f, "gl_missing", d->gl_missing);
    else fputs(", \"gl_missing\": null", f);
    fputc('}', f);
}

static void json_key_num(FILE *f, const char *key, double v)
{
    fprintf(f, ", \"%s\": ", key);
    json_num(f, v);
}

static void json_key_str(FILE *f, const char *key, const char *v)
{
    fprintf(f, ", \"%s\": ", key);
    json_str(f, v);
}

void hb_record_json(FILE *f, const hb_record *r)
{
    const hb_scene *s = &r->opt->scene;
    fputs("{\"backend\": ", f);
    json_str(f, r->backend);
    json_key_str(f, "variant", r->variant);
    json_key_str(f, "precision", hb_precision_name(s->precision));
    fprintf(f, ", \"strands\": %lld, \"points\": %lld, \"seed\": %llu", (long long)s->n_strands, (long long)s->points,
            (unsigned long long)s->seed);
    json_key_num(f, "head_radius", s->head_radius);
    json_key_num(f, "hair_offset", s->hair_offset);
    json_key_num(f, "hair_length", s->hair_length);
    json_key_num(f, "face_margin", s->face_margin);
    json_key_num(f, "wind_strength", s->wind_strength);
    json_key_num(f, "wind_angle", s->wind_angle);
    if (r->threads > 0) fprintf(f, ", \"threads\": %d", r->threads);
    else fputs(", \"threads\": null", f);
    if (r->block_size > 0) fprintf(f, ", \"block_size\": %d", r->block_size);
    else fputs(", \"block_size\": null", f);
    fprintf(f, ", \"repeat\": %d, \"warmup\": %d", r->opt->repeat, r->opt->warmup);
    json_key_str(f, "input", r->opt->input);
    json_key_str(f, "output", r->opt->output);
    if (r->opt->groom && r->groom) {
        fputs(", \"groom\": {\"source\": ", f);
        json_str(f, r->opt->groom);
        json_key_num(f, "length_min", r->groom->length_min);
        json_key_num(f, "length_max", r->groom->length_max);
        if (r->opt->scene.groom == HB_GROOM_CURLY) {
            json_key_num(f, "curl_radius", r->opt->scene.curl_radius);
            json_key_num(f, "curl_pitch", r->opt->scene.curl_pitch);
        } else {
            fprintf(f, ", \"file_strands\": %lld", (long long)r->groom->file_strands);
            json_key_num(f, "resample_error", r->groom->resample_error);
            /* the head sphere: fitted to the roots, or given by --head-center (docs/model.md §3.15) */
            json_key_str(f, "head", r->groom->head_given ? "given" : "fitted");
            fputs(", \"head_center\": [", f);
            for (int c = 0; c < 3; c++) {
                if (c) fputs(", ", f);
                json_num(f, r->groom->head_center[c]);
            }
            fputs("]", f);
            json_key_num(f, "fit_offset", r->groom->head_given ? NAN : r->groom->fit_offset);
        }
        fputs("}", f);
    }
    fputs(", \"stages\": [", f);
    for (int i = 0; i < r->n_stages; i++) {
        const hb_stage_record *st = &r->stages[i];
        fprintf(f, "%s{\"frame\": %d, \"stage\": ", i ? ", " : "", st->frame);
        json_str(f, st->meta.stage);
        fprintf(f, ", \"skipped\": %s, \"fused\": ", st->meta.skipped ? "true" : "false");
        json_str(f, st->meta.fused[0] ? st->meta.fused : NULL);
        json_key_num(f, "median_ms", st->meta.median_ms);
        json_key_num(f, "min_ms", st->meta.min_ms);
        json_key_num(f, "max_ms", st->meta.max_ms);
        fputs(", \"times_ms\": [", f);
        for (int k = 0; k < st->n_times; k++) {
            if (k) fputs(", ", f);
            json_num(f, st->times_ms[k]);
        }
        fputs("], \"moved_points\": ", f);
        if (st->meta.moved_points >= 0) fprintf(f, "%lld", (long long)st->meta.moved_points);
        else fputs("null", f);
        if (st->stage == HB_STAGE_SIMULATE) {
            const hb_dynamics *d = &s->dyn;
            fprintf(f, ", \"frames\": %lld, \"substeps\": %lld, \"iterations\": %lld, \"solver\": \"%s\"",
                    (long long)st->frames, (long long)d->substeps, (long long)d->iterations, hb_solver_name(d->solver));
            json_key_str(f, "features", st->features);
            if (st->layout[0] > 0)
                fprintf(f,
                        ", \"layout\": {\"points_a_lane\": %d, \"lanes_a_strand\": %d, \"block\": %d, "
                        "\"strands_a_wave\": %d}",
                        st->layout[0], st->layout[1], st->layout[2], st->layout[3]);
            else fputs(", \"layout\": null", f);
            fprintf(f, ", \"collider_sweeps\": %lld", (long long)d->collider_sweeps); /* §3.17 */
            if (d->planes_declared) json_key_num(f, "contact_planes", d->contact_margin);
            if (d->collide_once) fprintf(f, ", \"collide_once\": true"); /* §3.6 */
            json_key_num(f, "frame_dt", d->frame_dt);
            /* point-substeps per second of the median frame */
            json_key_num(f, "point_substeps_per_s",
                         (double)s->n_strands * (double)s->points * (double)d->substeps / (1e-3 * st->meta.median_ms));
            json_key_num(f, "observe_ms", st->observe_ms);
            json_key_num(f, "frame_loop_ms", st->loop_ms);
            json_key_num(f, "frame_loop_graph_ms", st->loop_graph_ms);
            /* §3.14: the written points a strand (null: as simulated) and one frame's rendering */
            if (d->render_points) fprintf(f, ", \"render_points\": %lld", (long long)d->render_points);
            else fputs(", \"render_points\": null", f);
            json_key_num(f, "render_ms", st->render_ms);
            json_draw(f, st);
            fputs(", \"last_observables\": {\"stretch_max\": ", f);
            json_num(f, st->last.stretch_max);
            json_key_num(f, "penetration_max", st->last.penetration_max);
            json_key_num(f, "kinetic_energy", st->last.kinetic_energy);
            fprintf(f, ", \"blown_up_strands\": %lld}, \"blown_up_frames\": %lld", (long long)st->last.blown_up_strands,
                    (long long)st->blown_frames);
        }
        fputc('}', f);
    }
    fputs("]", f);
    /* a blown-up simulation is flagged here and by the exit status (docs/interfaces.md) */
    fprintf(f, ", \"blown_up\": %s", hb_record_blown_frames(r) ? "true" : "false");
    json_key_num(f, "end_to_end_ms", r->end_to_end_ms);
    json_key_num(f, "h2d_ms", r->h2d_ms);
    json_key_num(f, "d2h_ms", r->d2h_ms);
    json_key_num(f, "hdf5_write_ms", r->hdf5_write_ms);
    fprintf(f, ", \"state_bytes\": %llu", (unsigned long long)hb_state_bytes(s));
    json_key_str(f, "git_revision", r->git_revision);
    json_key_str(f, "compiler", r->compiler);
    json_key_str(f, "flags", r->flags);
    json_key_str(f, "device", r->device);
    json_key_str(f, "driver", r->driver[0] ? r->driver : NULL);
    json_key_str(f, "version", HB_VERSION);
    fputs("}\n", f);
}

int64_t hb_record_blown_frames(const hb_record *r)
{
    int64_t n = 0;
    for (int i = 0; i < r->n_stages; i++)
        if (r->stages[i].stage == HB_STAGE_SIMULATE) n += r->stages[i].blown_frames;
    return n;
}

void hb_record_summary(FILE *f, const hb_record *r)
{
    const hb_scene *s = &r->opt->scene;
    fprintf(f, "hairsim %s/%s %s: %lld strands x %lld points on %s", r->backend, r->variant,
            hb_precision_name(s->precision), (long long)s->n_strands, (long long)s->points, r->device);
    if (r->threads > 0) fprintf(f, ", %d threads", r->threads);
    if (r->block_size > 0) fprintf(f, ", block %d", r->block_size);
    fputc('\n', f);
    for (int i = 0; i < r->n_stages; i++) {
        const hb_stage_record *st = &r->stages[i];
        fprintf(f, "  frame %-3d %-8s", st->frame, st->meta.stage);
        if (st->meta.skipped) fprintf(f, " skipped (nil effect: wind strength 0)");
        else if (strcmp(st->meta.fused, "into-previous") == 0) fprintf(f, " fused into the previous kernel");
        else
            fprintf(f, " median %.3f ms (min %.3f, max %.3f, %d runs)", st->meta.median_ms, st->meta.min_ms,
                    st->meta.max_ms, st->n_times);
        if (st->meta.moved_points >= 0) fprintf(f, ", %lld points moved", (long long)st->meta.moved_points);
        if (st->stage == HB_STAGE_SIMULATE) {
            fprintf(f, " per frame over %lld frames (%s, S=%lld, I=%lld, %s)", (long long)st->frames,
                    hb_solver_name(s->dyn.solver), (long long)s->dyn.substeps, (long long)s->dyn.iterations,
                    st->features);
            fprintf(f, "\n    last frame: stretch_max %.3g, penetration_max %.3g cm, kinetic energy %.6g cm2/s2",
                    st->last.stretch_max, st->last.penetration_max, st->last.kinetic_energy);
            if (st->blown_frames)
                fprintf(f, "; BLOWN UP in %lld frames (exit status %d)", (long long)st->blown_frames, HB_EXIT_BLOWN_UP);
        }
        fputc('\n', f);
    }
    if (isfinite(r->end_to_end_ms)) fprintf(f, "  end-to-end %.3f ms\n", r->end_to_end_ms);
    if (isfinite(r->hdf5_write_ms)) fprintf(f, "  HDF5 write %.3f ms -> %s\n", r->hdf5_write_ms, r->opt->output);
}
