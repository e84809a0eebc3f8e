/* SPDX-License-Identifier: MIT */
/* cd_access.c — what callers may read of a cd_sim (cd.h). */
#include "cd_impl.h"

ptl_state *cd_sim_particles(const cd_sim *s) { return s->p; }
double cd_sim_time(const cd_sim *s) { return s->t; }
long cd_sim_step_count(const cd_sim *s) { return s->step; }
const cd_box *cd_sim_box(const cd_sim *s) { return &s->box; }
const cd_config *cd_sim_config(const cd_sim *s) { return &s->cfg; }
long cd_sim_broken_bonds(const cd_sim *s) { return s->n_broken_bonds; }
void cd_sim_wall_times(const cd_sim *s, double *force, double *neighbour) {
  *force = s->wall_time_force;
  *neighbour = s->wall_time_neigh;
}
