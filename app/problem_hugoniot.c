/* SPDX-License-Identifier: MIT */
/* Built-in problem `hugoniot`: shock Hugoniots of deck materials, one CSV per material
 * (the reference curves validation runs are compared with). */
#include "commands.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct hugoniot_problem {
  size_t nmat;
  const eos_material **mat;
  double *up;
  size_t nup;
} hugoniot_problem;

void *hugoniot_problem_read(dk_doc *doc, const dk_node *section, const eos_materials *mats,
                            dk_errors *e) {
  hugoniot_problem *p = ms_calloc(1, sizeof *p);
  const dk_node *list = dk_get(section, "materials");
  if (!list)
    dk_error(e, doc, section, "hugoniot: missing required key 'materials' (a list of names)");
  else if (dk_expect_seq(e, doc, list, "hugoniot.materials")) {
    p->nmat = dk_seq_len(list);
    p->mat = ms_calloc(p->nmat, sizeof *p->mat);
    for (size_t i = 0; i < p->nmat; i++) {
      const dk_node *item = dk_seq_at(list, i);
      const char *name = dk_scalar(item);
      if (!name) dk_error(e, doc, item, "hugoniot.materials[%zu]: expected a material name", i);
      else p->mat[i] = eos_materials_find(mats, name, e, doc, item);
    }
  }
  if (dk_read_double_list(e, doc, section, "up", MS_DIM_VELOCITY, true, &p->up, &p->nup)) {
    const dk_node *n = dk_get(section, "up");
    for (size_t i = 0; i < p->nup; i++)
      if (!(p->up[i] > 0)) {
        dk_error(e, doc, n, "hugoniot.up[%zu]: particle velocities must be > 0, found %g", i,
                 p->up[i]);
        break;
      }
  }
  return p;
}

ms_status hugoniot_problem_run(ms_ctx *ctx, void *vp) {
  hugoniot_problem *p = vp;
  static const char *const names[] = {"up", "Us", "P", "rho", "e"};
  static const char *const units[] = {"km/s", "km/s", "GPa", "g/cm^3", "kJ/g"};
  eos_hugoniot_point *pts = ms_calloc(p->nup, sizeof *pts);
  ms_status s = MS_OK;
  for (size_t m = 0; m < p->nmat && !s; m++) {
    const eos_material *mat = p->mat[m];
    s = eos_hugoniot(mat->eos, eos_rho0(mat->eos), eos_e0(mat->eos), p->nup, p->up, pts);
    if (s) {
      ms_log(ctx, MS_LOG_ERROR, "Hugoniot of '%s': %s", mat->name, ms_status_str(s));
      break;
    }
    if (ctx->rank != 0) continue;
    char file[300];
    snprintf(file, sizeof file, "hugoniot_%s.csv", mat->name);
    char *path = ms_out_path(ctx, file);
    ms_afile af;
    s = ms_afile_open(&af, path);
    if (!s) {
      char title[400];
      snprintf(title, sizeof title,
               "Shock Hugoniot of %s (%s EOS) from rho0 = %g g/cm^3, e0 = %g kJ/g", mat->name,
               eos_kind_name(eos_get_kind(mat->eos)), eos_rho0(mat->eos), eos_e0(mat->eos));
      ms_csv_header(af.f, title, 5, names, units);
      for (size_t i = 0; i < p->nup; i++) {
        double row[5] = {pts[i].up, pts[i].us, pts[i].p, pts[i].rho, pts[i].e};
        ms_csv_row(af.f, 5, row);
      }
      s = ms_afile_commit(&af);
    }
    ms_log(ctx, MS_LOG_INFO, "Hugoniot of %s: %zu points -> %s", mat->name, p->nup, path);
    free(path);
  }
  free(pts);
  return s;
}

void hugoniot_problem_destroy(void **vp) {
  hugoniot_problem *p = vp ? *vp : NULL;
  if (!p) return;
  free(p->mat);
  free(p->up);
  free(p);
  *vp = NULL;
}
