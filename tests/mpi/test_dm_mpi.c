/* SPDX-License-Identifier: MIT */
/* The discrete model on MPI ranks (docs/mpi.md), run under mpirun -np 1, 2, 3:
 *  - a 3D block with random velocities, every boundary kind at once (clamped wall and
 *    symmetry mirrors, a fixed layer, a periodic axis, hourglass stabilisation, a 3-stage
 *    scheme) and the spherical source (prescribed particles, three symmetry planes): each
 *    rank also runs the same deck on one rank in-process (a serial context), and the
 *    distributed run must reproduce it BIT FOR BIT — particle counts, every displacement and
 *    velocity, energies and the hourglass indicator. Tolerance 0 by design: owned particles
 *    are computed by the same code from the same operands in the same order, and every global
 *    sum runs in global particle order (docs/mpi.md, "Determinism");
 *  - METIS partition quality against plain x slabs (printed; imbalance asserted);
 *  - checkpoint/restart: a run to 2N steps writing a checkpoint at N, then restarts from it on
 *    this rank count and on one rank, must end bitwise equal to the uninterrupted run; an
 *    interrupted checkpoint write (a truncated dm_checkpoint.h5.part left behind) does not
 *    touch the previous checkpoint, which still restarts, and restarting from the truncated
 *    file fails cleanly. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h> /* dm_test.h's deck reader asserts on the literal decks below only */

#include "dm/dm_test.h"
#include "mpi_check.h"

static const char *block_deck =
    "problem: discrete_model\n"
    "materials:\n"
    "  - name: steel\n"
    "    eos: {type: linear_elastic, rho0: 7.85, bulk_modulus: 133.33333333333333}\n"
    "    shear_modulus: 80.0\n"
    "  - name: al\n"
    "    eos: {type: linear_elastic, rho0: 2.71, bulk_modulus: 77.56675}\n"
    "    shear_modulus: 26.0\n"
    "discrete_model:\n"
    "  dimension: 3\n"
    "  spacing: 0.1\n"
    "  domain: {lo: [0, 0, 0], hi: [1.2, 0.8, 0.8]}\n"
    "  horizon: 2.0\n"
    "  boundaries: {x_lo: wall, x_hi: free, y_lo: periodic, y_hi: periodic,\n"
    "               z_lo: symmetry, z_hi: fixed}\n"
    "  layers:\n"
    "    - {material: steel, x_max: 0.55}\n"
    "    - {material: al}\n"
    "  initial: {profile: random_velocity, amplitude: 0.01, seed: 7}\n"
    "  hourglass: 0.5\n"
    "  integrator: rkn4\n"
    "  courant: 0.4\n"
    "  steps: %ld\n"
    "  output: {energy_every: 10, probes: [0.35, 0.95], checkpoint_every: %ld}\n";

static const char *sphere_deck =
    "problem: discrete_model\n"
    "materials:\n"
    "  - name: steel\n"
    "    eos: {type: linear_elastic, rho0: 7.85, bulk_modulus: 133.33333333333333}\n"
    "    shear_modulus: 80.0\n"
    "discrete_model:\n"
    "  dimension: 3\n"
    "  spacing: 0.25\n"
    "  domain: {lo: [0, 0, 0], hi: [3.0, 3.0, 3.0]}\n"
    "  horizon: 1.5\n"
    "  boundaries: {x_lo: symmetry, y_lo: symmetry, z_lo: symmetry}\n"
    "  layers:\n"
    "    - {material: steel}\n"
    "  source: {type: sphere, r0: 0.6, w0: 0.01, period: 0.5}\n"
    "  integrator: verlet\n"
    "  courant: 0.5\n"
    "  t_end: 0.3\n"
    "  output: {energy_every: 5, checkpoint_every: %ld}\n";

/* Runs the deck on ctx (restart: checkpoint path or NULL); result kept in L. */
static ms_status run(dm_test_problem *L, const char *text, ms_ctx *ctx, const char *restart) {
  dm_test_problem_read(L, text);
  if (!L->p) {
    dk_errors_print(&L->e, stderr);
    return MS_ERR_INPUT;
  }
  ctx->restart = restart;
  ms_status st = dm_problem_run(ctx, L->p);
  ctx->restart = NULL;
  return st;
}

/* Bitwise comparison of two runs' end states and summaries (== on doubles: −0 and +0 agree,
 * NaN fields are compared by their NaN-ness). */
static void same_run(const dm_test_problem *a, const dm_test_problem *b, const char *what) {
  const double *wa, *ua, *wb, *ub;
  size_t na = dm_problem_final_state(a->p, &wa, &ua), nb = dm_problem_final_state(b->p, &wb, &ub);
  CHECK(na == nb && na > 0, "%s: particle counts %zu vs %zu", what, na, nb);
  if (na != nb) return;
  size_t bad = 0, first = 0;
  for (size_t i = 0; i < 3 * na; ++i)
    if (wa[i] != wb[i] || ua[i] != ub[i]) {
      if (!bad) first = i;
      ++bad;
    }
  CHECK(bad == 0, "%s: %zu components differ (first: particle %zu, w %.17g vs %.17g)", what, bad,
        first / 3, wa[first], wb[first]);
  const dm_run_summary *sa = dm_problem_summary(a->p), *sb = dm_problem_summary(b->p);
#define SAME(f)                                                                                    \
  CHECK(sa->f == sb->f || (isnan(sa->f) && isnan(sb->f)), "%s: " #f " %.17g vs %.17g", what,       \
        (double)sa->f, (double)sb->f)
  CHECK(sa->particles == sb->particles && sa->real_particles == sb->real_particles &&
            sa->bonds == sb->bonds && sa->steps == sb->steps,
        "%s: particle, bond or step counts differ", what);
  SAME(kinetic_end);
  SAME(potential_end);
  SAME(omega_dt);
  SAME(energy_err_max);
  SAME(hourglass_first);
  SAME(hourglass_max);
  SAME(hourglass_last);
  SAME(err_l2);
  SAME(err_u_l2);
#undef SAME
}

int main(int argc, char **argv) {
  ms_ctx ctx, serial;
  ms_ctx_init_serial(&ctx);
  if (par_init(&argc, &argv, &ctx)) return 1;
  ms_ctx_init_serial(&serial); /* rank-local reference run: no communication at all */
  serial.verbosity = MS_LOG_WARN;
  ctx.verbosity = MS_LOG_WARN;
  const int np = ctx.size;
  char text[4096];

  /* 1. block: distributed run == one-rank run, bit for bit */
  const long nsteps = 60;
  snprintf(text, sizeof text, block_deck, nsteps, 0L);
  dm_test_problem ref, dist;
  CHECK(run(&ref, text, &serial, NULL) == MS_OK, "block, serial reference");
  CHECK(run(&dist, text, &ctx, NULL) == MS_OK, "block, %d ranks", np);
  if (ref.p && dist.p) {
    same_run(&ref, &dist, "block");
    const dm_run_summary *s = dm_problem_summary(dist.p);
    /* the random velocities must have done something: energy exchanged with the bonds */
    CHECK(s->potential_end > 0.05 * s->kinetic_end, "block: potential energy %g, kinetic %g",
          s->potential_end, s->kinetic_end);
    /* a sanity bound only: with mirror ghosts the reported energy is not exactly the
     * Hamiltonian (docs/particles-dm.md), it drifts by ~10 % over this run */
    CHECK(s->energy_err_max < 0.5, "block: energy error %g", s->energy_err_max);
    if (ctx.rank == 0)
      printf("block (%zu particles, %zu bonds) on %d ranks: METIS edge cut %ld (imbalance %.4f), "
             "plain x slabs %ld (imbalance %.4f)\n",
             s->particles, s->bonds / 2, np, s->edge_cut, s->imbalance, s->edge_cut_slab,
             s->imbalance_slab);
    if (np > 1) {
      /* METIS is asked for at most 1 % above the mean weight (ufactor 10; docs/mpi.md); a
       * little slack for the graph's granularity */
      CHECK(s->imbalance <= 1.02, "METIS imbalance %g", s->imbalance);
      CHECK(s->edge_cut > 0 && s->edge_cut_slab > 0, "edge cuts %ld, %ld", s->edge_cut,
            s->edge_cut_slab);
    } else {
      CHECK(s->edge_cut == 0, "one rank cuts nothing");
    }
  }
  dm_test_problem_free(&ref);
  dm_test_problem_free(&dist);

  /* 2. spherical source (prescribed particles + mirror ghosts of them) */
  snprintf(text, sizeof text, sphere_deck, 0L);
  CHECK(run(&ref, text, &serial, NULL) == MS_OK, "sphere, serial reference");
  CHECK(run(&dist, text, &ctx, NULL) == MS_OK, "sphere, %d ranks", np);
  if (ref.p && dist.p) same_run(&ref, &dist, "sphere");
  dm_test_problem_free(&ref);
  dm_test_problem_free(&dist);

  /* 3. checkpoint / restart: 2N steps with a checkpoint at N */
  char dirA[64], ckpt[128], part[160];
  snprintf(dirA, sizeof dirA, "dm_mpi_np%d_ckpt", np);
  snprintf(ckpt, sizeof ckpt, "%s/dm_checkpoint.h5", dirA);
  snprintf(part, sizeof part, "%s.part", ckpt);
  ms_status st = par_agree_status(ms_outdir_create(&ctx, dirA, true));
  CHECK(st == MS_OK, "output directory");
  snprintf(text, sizeof text, block_deck, 2 * nsteps, nsteps);
  dm_test_problem full, again, other;
  CHECK(run(&full, text, &ctx, NULL) == MS_OK, "run to 2N with a checkpoint at N");
  par_barrier();
  FILE *f = fopen(ckpt, "rb");
  CHECK(f != NULL, "checkpoint %s written", ckpt);
  if (f) fclose(f);
  /* the restarts write no files: the checkpoint stays as it is */
  ms_ctx quiet_ctx = ctx;
  static char none[1] = "";
  quiet_ctx.outdir = none;
  CHECK(run(&again, text, &quiet_ctx, ckpt) == MS_OK, "restart on %d ranks", np);
  CHECK(run(&other, text, &serial, ckpt) == MS_OK, "restart on 1 rank");
  if (full.p && again.p) {
    same_run(&full, &again, "restart, same rank count");
    CHECK(dm_problem_summary(again.p)->restart_step == nsteps, "restart step %ld",
          dm_problem_summary(again.p)->restart_step);
  }
  if (full.p && other.p) same_run(&full, &other, "restart, 1 rank");
  dm_test_problem_free(&again);
  dm_test_problem_free(&other);

  /* 4. a write interrupted by a crash leaves CHECKPOINT.part, never a damaged CHECKPOINT:
   * simulate it with the first half of a valid file under the .part name */
  if (ctx.rank == 0) {
    FILE *in = fopen(ckpt, "rb"), *out = fopen(part, "wb");
    if (in && out) {
      fseek(in, 0, SEEK_END);
      long size = ftell(in);
      fseek(in, 0, SEEK_SET);
      char *buf = malloc((size_t)size);
      size_t got = fread(buf, 1, (size_t)size, in);
      fwrite(buf, 1, got / 2, out);
      free(buf);
    }
    if (in) fclose(in);
    if (out) fclose(out);
  }
  par_barrier();
  CHECK(run(&again, text, &quiet_ctx, ckpt) == MS_OK, "restart with a stale .part beside it");
  if (full.p && again.p) same_run(&full, &again, "restart after an interrupted write");
  dm_test_problem_free(&again);
  /* (the error it logs is expected) */
  CHECK(run(&again, text, &quiet_ctx, part) != MS_OK, "restart from a truncated file must fail");
  dm_test_problem_free(&again);
  dm_test_problem_free(&full);

  ms_ctx_close(&serial);
  ms_ctx_close(&ctx);
  int all = (int)par_sum_long(failures);
  if (ctx.rank == 0) printf("%s: %d failure(s) over %d rank(s)\n", all ? "FAILED" : "OK", all, np);
  par_finalize();
  return all ? 1 : 0;
}
