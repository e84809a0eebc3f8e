/* SPDX-License-Identifier: MIT */
/* regions.c — the particle models that implement ptl_region.h, by their deck names. */
#include "cd.h"
#include "dm.h"

#include <string.h>

const char *const ptl_region_model_names[] = {"cluster_dynamics", "discrete_model", NULL};

const ptl_region_model *ptl_region_model_find(const char *name) {
  if (name && !strcmp(name, "cluster_dynamics")) return cd_region_model_get();
  if (name && !strcmp(name, "discrete_model")) return dm_region_model_get();
  return NULL;
}
