/* SPDX-License-Identifier: MIT */
/* materials.c — the deck's `materials:` list (and optional `mixtures:` list), docs/eos.md.
 *
 * Every value goes through the dk_read_* readers with its dimension, so `units: si` decks are
 * converted. Impossible values are errors at the value's FILE:LINE:COL; unknown keys inside
 * these sections are reported here with the list of accepted keys (and then marked used, so
 * the front end's dk_report_unused does not report them twice). */
#include "eos_impl.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const eos_type_names[] = {
    "mg_cold", "mg_linear", "ideal_gas", "table_cold", "table_full", "linear_elastic", NULL};
static const eos_kind eos_type_kinds[] = {EOS_MG_COLD,    EOS_MG_LINEAR,  EOS_IDEAL_GAS,
                                          EOS_TABLE_COLD, EOS_TABLE_FULL, EOS_LINEAR_ELASTIC};
static const char *const gamma_models[] = {"constant", "rho_gamma", NULL};

/* Keys accepted in each eos: mapping (same order as eos_type_names). */
static const char *const eos_keys[][8] = {
    {"type", "rho0", "c0", "n", "gamma0", "gamma_model", "cv", NULL},
    {"type", "rho0", "c0", "s", "gamma0", "cv", NULL},
    {"type", "gamma", "rho0", "p0", "cv", NULL},
    {"type", "file", "gamma0", "gamma_model", "cv", NULL},
    {"type", "file", "cv", NULL},
    {"type", "rho0", "bulk_modulus", NULL},
};
static const char *const material_keys[] = {"name", "eos", "shear_modulus", "viscosity", NULL};
static const char *const mixture_keys[] = {"name", "components", NULL};
static const char *const component_keys[] = {"material", "volume_fraction", "mass_fraction", NULL};

static bool in_list(const char *key, const char *const *list) {
  for (size_t i = 0; list[i]; ++i)
    if (strcmp(key, list[i]) == 0) return true;
  return false;
}

/* Report keys of `map` that are not in `allowed`, then mark them used. */
static void check_keys(dk_errors *e, const dk_doc *doc, const dk_node *map, const char *what,
                       const char *const *allowed) {
  for (size_t i = 0; i < dk_map_len(map); ++i) {
    const char *key = dk_map_key(map, i);
    if (in_list(key, allowed)) continue;
    dk_report_unknown_key(e, doc, map, i, what, allowed);
    (void)dk_get(map, key);
  }
}

/* A number with an exclusive lower bound given in the message (n > 1, γ > 1). */
static bool read_greater_than(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key,
                              const char *what, double bound, double *out) {
  if (!dk_read_double(e, doc, map, key, MS_DIM_NONE, true, 0.0, -INFINITY, INFINITY, out))
    return false;
  if (!(*out > bound)) {
    dk_error(e, doc, dk_get(map, key), "%s.%s: expected a number > %g, found %g", what, key, bound,
             *out);
    return false;
  }
  return true;
}

/* Resolve a data-file path and check it exists; error at the `file:` value otherwise. */
static char *read_file_key(dk_errors *e, dk_doc *doc, const dk_node *map, const char *what) {
  const char *file;
  if (!dk_read_string(e, doc, map, "file", true, NULL, &file)) return NULL;
  char *path = dk_resolve_path(doc, file);
  FILE *f = fopen(path, "r");
  if (!f) {
    dk_error(e, doc, dk_get(map, "file"),
             "%s.file: cannot open table file '%s' (resolved to '%s'): %s", what, file, path,
             strerror(errno));
    free(path);
    return NULL;
  }
  fclose(f);
  return path;
}

static eos_t *read_eos(dk_errors *e, dk_doc *doc, const dk_node *eosmap, const char *what) {
  int type;
  if (!dk_read_enum(e, doc, eosmap, "type", true, 0, eos_type_names, &type)) {
    /* the other keys cannot be checked without a type: mark them used (no cascade) */
    for (size_t i = 0; i < dk_map_len(eosmap); ++i) (void)dk_get(eosmap, dk_map_key(eosmap, i));
    return NULL;
  }
  check_keys(e, doc, eosmap, what, eos_keys[type]);
  eos_kind kind = eos_type_kinds[type];
  size_t nerr0 = e->n;
  double rho0 = 0, c0 = 0, n = 0, s = 0, gamma0 = 0, gamma = 0, p0 = 0, K = 0;
  int gm = 0;
  eos_t *eos = NULL;
  switch (kind) {
  case EOS_MG_COLD:
    dk_read_positive(e, doc, eosmap, "rho0", MS_DIM_DENSITY, true, 0, &rho0);
    dk_read_positive(e, doc, eosmap, "c0", MS_DIM_VELOCITY, true, 0, &c0);
    read_greater_than(e, doc, eosmap, "n", what, 1.0, &n);
    dk_read_double(e, doc, eosmap, "gamma0", MS_DIM_NONE, true, 0, 0.0, INFINITY, &gamma0);
    dk_read_enum(e, doc, eosmap, "gamma_model", false, 0, gamma_models, &gm);
    if (e->n == nerr0) eos = eos_create_mg_cold(rho0, c0, n, gamma0, gm == 1);
    break;
  case EOS_MG_LINEAR:
    dk_read_positive(e, doc, eosmap, "rho0", MS_DIM_DENSITY, true, 0, &rho0);
    dk_read_positive(e, doc, eosmap, "c0", MS_DIM_VELOCITY, true, 0, &c0);
    dk_read_double(e, doc, eosmap, "s", MS_DIM_NONE, true, 0, 0.0, INFINITY, &s);
    dk_read_double(e, doc, eosmap, "gamma0", MS_DIM_NONE, true, 0, 0.0, INFINITY, &gamma0);
    if (e->n == nerr0) eos = eos_create_mg_linear(rho0, c0, s, gamma0);
    break;
  case EOS_IDEAL_GAS:
    read_greater_than(e, doc, eosmap, "gamma", what, 1.0, &gamma);
    /* Defaults: air at 15 °C, 1 atm (the reference state for eos_c0 and Hugoniots). */
    dk_read_positive(e, doc, eosmap, "rho0", MS_DIM_DENSITY, false, 1.225e-3, &rho0);
    dk_read_double(e, doc, eosmap, "p0", MS_DIM_PRESSURE, false, 1.01325e-4, 0.0, INFINITY, &p0);
    if (e->n == nerr0) eos = eos_create_ideal_gas_ref(gamma, rho0, p0);
    break;
  case EOS_LINEAR_ELASTIC:
    dk_read_positive(e, doc, eosmap, "rho0", MS_DIM_DENSITY, true, 0, &rho0);
    dk_read_positive(e, doc, eosmap, "bulk_modulus", MS_DIM_PRESSURE, true, 0, &K);
    if (e->n == nerr0) eos = eos_create_linear_elastic(rho0, K);
    break;
  case EOS_TABLE_COLD: {
    dk_read_double(e, doc, eosmap, "gamma0", MS_DIM_NONE, true, 0, 0.0, INFINITY, &gamma0);
    dk_read_enum(e, doc, eosmap, "gamma_model", false, 0, gamma_models, &gm);
    char *path = read_file_key(e, doc, eosmap, what);
    if (path && e->n == nerr0) {
      eos = eos_create_table_cold(path, gamma0, gm == 1, e);
      if (!eos)
        dk_error(e, doc, dk_get(eosmap, "file"),
                 "%s.file: invalid cold-curve table '%s' (see above)", what,
                 dk_scalar(dk_get(eosmap, "file")));
    }
    free(path);
    break;
  }
  case EOS_TABLE_FULL: {
    char *path = read_file_key(e, doc, eosmap, what);
    if (path) {
      eos = eos_create_table_full(path, e);
      if (!eos)
        dk_error(e, doc, dk_get(eosmap, "file"), "%s.file: invalid EOS table '%s' (see above)",
                 what, dk_scalar(dk_get(eosmap, "file")));
    }
    free(path);
    break;
  }
  }
  if (!eos && e->n == nerr0)
    dk_error(e, doc, eosmap, "%s: the parameters do not define a valid %s EOS", what,
             eos_type_names[type]);
  /* Optional constant specific heat for temperatures, kJ/(g·K) (J/(kg·K) in SI decks: the
   * conversion is that of a specific energy, kelvin being the same in both systems). */
  if (kind != EOS_LINEAR_ELASTIC && dk_get(eosmap, "cv")) {
    double cv = 0.0;
    if (dk_read_positive(e, doc, eosmap, "cv", MS_DIM_SPEC_ENERGY, true, 0, &cv) && eos)
      eos_set_heat_capacity(eos, cv);
  }
  return eos;
}

static void add_broken(eos_materials *mats, const char *name) {
  if (!name) return;
  mats->broken = ms_realloc(mats->broken, mats->nbroken + 1, sizeof *mats->broken);
  mats->broken[mats->nbroken++] = ms_strdup(name);
}

static const eos_material *find_material(const eos_materials *mats, const char *name) {
  for (size_t i = 0; i < mats->n; ++i)
    if (strcmp(mats->m[i].name, name) == 0) return &mats->m[i];
  return NULL;
}

static bool is_broken(const eos_materials *mats, const char *name) {
  for (size_t i = 0; i < mats->nbroken; ++i)
    if (strcmp(mats->broken[i], name) == 0) return true;
  return false;
}

const eos_material *eos_materials_find(const eos_materials *mats, const char *name, dk_errors *e,
                                       const dk_doc *doc, const dk_node *where) {
  if (!mats || !name) return NULL;
  const eos_material *m = find_material(mats, name);
  if (m || !e || is_broken(mats, name)) return m;
  /* The names the deck defines, those with errors of their own included (they are defined,
   * only not usable): "known: none defined" after one broken material misleads. */
  char known[600] = "";
  const char **names = ms_calloc(mats->n + mats->nbroken + 1, sizeof *names);
  size_t nn = 0;
  for (size_t i = 0; i < mats->n; ++i) names[nn++] = mats->m[i].name;
  for (size_t i = 0; i < mats->nbroken; ++i) names[nn++] = mats->broken[i];
  for (size_t i = 0; i < nn; ++i) {
    size_t len = strlen(known);
    snprintf(known + len, sizeof known - len, "%s%s", i ? ", " : "", names[i]);
  }
  const char *hint = dk_suggest(name, names);
  if (hint) dk_error(e, doc, where, "unknown material '%s' (did you mean '%s'?)", name, hint);
  else
    dk_error(e, doc, where, "unknown material '%s' (known: %s)", name, nn ? known : "none defined");
  free(names);
  return NULL;
}

const eos_mixture *eos_mixtures_find(const eos_materials *mats, const char *name) {
  if (!mats || !name) return NULL;
  for (size_t i = 0; i < mats->nmix; ++i)
    if (strcmp(mats->mix[i].name, name) == 0) return &mats->mix[i];
  return NULL;
}

/* Where a name was first defined (line), or 0. */
static int name_line(const dk_node *list, size_t upto, const char *name) {
  for (size_t i = 0; i < upto; ++i) {
    const dk_node *it = dk_seq_at(list, i);
    const char *other = dk_scalar(dk_get(it, "name"));
    if (other && strcmp(other, name) == 0) return dk_node_line(it);
  }
  return 0;
}

/* Entry i of a list of named entries (materials, mixtures): a mapping with only the `keys`,
 * whose `name` no earlier entry has. Sets `what` to "LIST[i]" and *name (NULL if missing);
 * returns the entry, or NULL if it is not a mapping. */
static const dk_node *named_item(dk_errors *e, dk_doc *doc, const dk_node *list, size_t i,
                                 const char *list_name, const char *noun, const char *const *keys,
                                 char what[64], const char **name) {
  const dk_node *item = dk_seq_at(list, i);
  snprintf(what, 64, "%s[%zu]", list_name, i);
  *name = NULL;
  if (!dk_expect_map(e, doc, item, what)) return NULL;
  check_keys(e, doc, item, what, keys);
  dk_read_string(e, doc, item, "name", true, NULL, name);
  const int first = *name ? name_line(list, i, *name) : 0;
  if (first)
    dk_error(e, doc, dk_get(item, "name"),
             "%s.name: duplicate %s name '%s' (first defined on line %d)", what, noun, *name,
             first);
  return item;
}

static void read_mixtures(dk_errors *e, dk_doc *doc, const dk_node *list, eos_materials *mats) {
  if (!dk_expect_seq(e, doc, list, "mixtures")) return;
  size_t n = dk_seq_len(list);
  mats->mix = ms_calloc(n ? n : 1, sizeof *mats->mix);
  for (size_t i = 0; i < n; ++i) {
    char what[64];
    const char *name;
    size_t nerr0 = e->n;
    const dk_node *item =
        named_item(e, doc, list, i, "mixtures", "mixture", mixture_keys, what, &name);
    if (!item) continue;
    if (name && !name_line(list, i, name) && (find_material(mats, name) || is_broken(mats, name)))
      dk_error(e, doc, dk_get(item, "name"), "%s.name: '%s' is already the name of a material",
               what, name);
    const dk_node *comps = dk_get(item, "components");
    if (!comps) {
      dk_error(e, doc, item,
               "%s: missing required key 'components' (a list of {material: NAME, "
               "volume_fraction: X} or {material: NAME, mass_fraction: X})",
               what);
      continue;
    }
    if (!dk_expect_seq(e, doc, comps, "components")) continue;
    size_t nc = dk_seq_len(comps);
    if (nc == 0) {
      dk_error(e, doc, comps, "%s.components: expected at least one component", what);
      continue;
    }
    size_t *idx = ms_calloc(nc, sizeof *idx);
    double *frac = ms_calloc(nc, sizeof *frac);
    int by_mass = -1; /* unknown yet; all components must use the same kind of fraction */
    bool all_found = true;
    for (size_t k = 0; k < nc; ++k) {
      const dk_node *c = dk_seq_at(comps, k);
      char cw[128];
      snprintf(cw, sizeof cw, "%s.components[%zu]", what, k);
      if (!dk_expect_map(e, doc, c, cw)) continue;
      check_keys(e, doc, c, cw, component_keys);
      const char *mname = NULL;
      if (dk_read_string(e, doc, c, "material", true, NULL, &mname)) {
        const eos_material *m = eos_materials_find(mats, mname, e, doc, dk_get(c, "material"));
        if (m) idx[k] = (size_t)(m - mats->m);
        else all_found = false; /* a material with errors of its own (already reported) */
      }
      bool has_vol = dk_get(c, "volume_fraction") != NULL,
           has_mass = dk_get(c, "mass_fraction") != NULL;
      if (has_vol == has_mass) {
        dk_error(e, doc, c, "%s: give exactly one of volume_fraction or mass_fraction", cw);
        continue;
      }
      if (by_mass >= 0 && by_mass != (int)has_mass) {
        dk_error(e, doc, c, "%s: mixes volume and mass fractions; use one kind for all components",
                 cw);
        continue;
      }
      by_mass = has_mass;
      dk_read_double(e, doc, c, has_mass ? "mass_fraction" : "volume_fraction", MS_DIM_NONE, true,
                     0, 0.0, 1.0, &frac[k]);
    }
    double sum = 0.0;
    for (size_t k = 0; k < nc; ++k) sum += frac[k];
    if (e->n == nerr0 && fabs(sum - 1.0) > 1e-6)
      dk_error(e, doc, comps, "%s.components: fractions must add up to 1, found %.9g", what, sum);
    if (e->n != nerr0 || !all_found) {
      free(idx), free(frac);
      continue;
    }
    if (by_mass == 1) { /* α_i = (y_i/ρ0_i) / Σ (y_k/ρ0_k) */
      double vsum = 0.0;
      for (size_t k = 0; k < nc; ++k) vsum += frac[k] / eos_rho0(mats->m[idx[k]].eos);
      for (size_t k = 0; k < nc; ++k) frac[k] = frac[k] / eos_rho0(mats->m[idx[k]].eos) / vsum;
    }
    eos_mixture *mx = &mats->mix[mats->nmix++];
    mx->name = ms_strdup(name);
    mx->ncomp = nc;
    mx->comp = idx;
    mx->alpha = frac;
  }
}

eos_materials *eos_materials_read(dk_doc *doc, dk_errors *e) {
  const dk_node *root = dk_root(doc);
  const dk_node *list = dk_get(root, "materials");
  if (!list) {
    dk_error(
        e, doc, root,
        "missing required top-level key 'materials' (a list of {name: NAME, eos: {type: ...}})");
    return NULL;
  }
  if (!dk_expect_seq(e, doc, list, "materials")) return NULL;
  size_t n = dk_seq_len(list);
  eos_materials *mats = ms_calloc(1, sizeof *mats);
  mats->m = ms_calloc(n ? n : 1, sizeof *mats->m);
  if (n == 0) dk_error(e, doc, list, "materials: the list is empty (define at least one material)");
  for (size_t i = 0; i < n; ++i) {
    char what[64];
    const char *name;
    size_t nerr0 = e->n;
    const dk_node *item =
        named_item(e, doc, list, i, "materials", "material", material_keys, what, &name);
    if (!item) continue;
    double shear = 0.0, visc = 0.0;
    if (dk_get(item, "shear_modulus"))
      dk_read_double(e, doc, item, "shear_modulus", MS_DIM_PRESSURE, true, 0, 0.0, INFINITY,
                     &shear);
    if (dk_get(item, "viscosity"))
      dk_read_double(e, doc, item, "viscosity", MS_DIM_VISCOSITY, true, 0, 0.0, INFINITY, &visc);
    const dk_node *eosmap = dk_get(item, "eos");
    eos_t *eos = NULL;
    char eos_what[96];
    snprintf(eos_what, sizeof eos_what, "%s.eos", what);
    if (!eosmap)
      dk_error(e, doc, item, "%s%s%s%s: missing required key 'eos' (a mapping {type: ..., ...})",
               what, name ? " ('" : "", name ? name : "", name ? "')" : "");
    else if (dk_expect_map(e, doc, eosmap, eos_what)) eos = read_eos(e, doc, eosmap, eos_what);
    if (!eos || e->n != nerr0) {
      eos_destroy(&eos);
      /* a duplicate is not "broken": the first definition stands */
      if (name && !find_material(mats, name)) add_broken(mats, name);
      continue;
    }
    eos_material *m = &mats->m[mats->n++];
    m->name = ms_strdup(name);
    m->eos = eos;
    m->shear_modulus = shear;
    m->viscosity = visc;
    m->line = dk_node_line(item);
    m->col = dk_node_col(item);
  }
  const dk_node *mixtures = dk_get(root, "mixtures");
  if (mixtures) read_mixtures(e, doc, mixtures, mats);
  return mats;
}

static void eos_materials_free(eos_materials *mats) {
  if (!mats) return;
  for (size_t i = 0; i < mats->n; ++i) {
    free(mats->m[i].name);
    eos_destroy(&mats->m[i].eos);
  }
  free(mats->m);
  for (size_t i = 0; i < mats->nmix; ++i) {
    free(mats->mix[i].name);
    free(mats->mix[i].comp);
    free(mats->mix[i].alpha);
  }
  free(mats->mix);
  for (size_t i = 0; i < mats->nbroken; ++i) free(mats->broken[i]);
  free(mats->broken);
  free(mats);
}

void eos_materials_destroy(eos_materials **mats) {
  if (!mats) return;
  eos_materials_free(*mats);
  *mats = NULL;
}
