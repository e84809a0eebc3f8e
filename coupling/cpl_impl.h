/* cpl_impl.h — internal helpers shared by the coupling sources (not part of the API). */
#ifndef MSCALE_CPL_IMPL_H
#define MSCALE_CPL_IMPL_H

#include "cpl.h"

/* Strict C11 + POSIX does not define M_PI. */
#define CPL_PI 3.14159265358979323846

/* Scratch columns per fragment in cpl_fragments.work. */
#define CPL_WORK_COLS 10

/* The largest fragment by mass (lowest id on ties); (size_t)-1 if there is none. */
size_t cpl_largest_fragment(const cpl_fragments *f);
/* cpl_is_ejecta with the largest fragment already known. */
bool cpl_is_ejecta_with(const cpl_fragments *f, size_t k, const cpl_ejecta_sel *s, size_t largest);

#endif
