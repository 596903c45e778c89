/* lsm_names: an enum and its names from one list.
 *
 * Each option enum is written once as an X-macro list of (identifier, name),
 * declared with its name functions in a header:
 *
 *   #define LSM_SCHEME_LIST(X) X(LSM_SCHEME_UPWIND, "upwind") X(LSM_SCHEME_ROEFIX, "roe-fix")
 *   LSM_ENUM(lsm_scheme, LSM_SCHEME, LSM_SCHEME_LIST, lsm_scheme_name, lsm_scheme_from_name);
 *
 * which gives LSM_SCHEME_UNKNOWN (-1), the listed values and LSM_SCHEME_COUNT;
 * one line in a .c file defines the name <-> value functions:
 *
 *   LSM_NAME_FUNCTIONS(lsm_scheme, LSM_SCHEME_LIST, lsm_scheme_name, lsm_scheme_from_name)
 *
 * `to_name` gives "unknown" for a value outside the list; `from_name` gives -1
 * (the enum's UNKNOWN) for a name outside it, or NULL.
 */
#ifndef LSM_NAMES_H
#define LSM_NAMES_H

#include <string.h>

#define LSM_ENUM_ITEM(id, text) id,
#define LSM_ENUM_TEXT(id, text) text,

/* Index of `name` in names[0 .. count-1], or -1. */
static inline int lsm_name_index(const char *const *names, int count, const char *name) {
  for (int k = 0; name && k < count; ++k)
    if (strcmp(name, names[k]) == 0) return k;
  return -1;
}

#define LSM_ENUM(type, PREFIX, LIST, to_name, from_name)                      \
  typedef enum type { PREFIX##_UNKNOWN = -1, LIST(LSM_ENUM_ITEM) PREFIX##_COUNT } type; \
  const char *to_name(type value);                                                \
  type from_name(const char *name)

#define LSM_NAME_FUNCTIONS(type, LIST, to_name, from_name)                        \
  static const char *const to_name##_table_[] = {LIST(LSM_ENUM_TEXT)};            \
  enum { to_name##_count_ = (int)(sizeof to_name##_table_ / sizeof *to_name##_table_) }; \
  const char *to_name(type value) {                                               \
    return (int)value >= 0 && (int)value < to_name##_count_ ? to_name##_table_[value] \
                                                             : "unknown";          \
  }                                                                               \
  type from_name(const char *name) {                                              \
    return (type)lsm_name_index(to_name##_table_, to_name##_count_, name);        \
  }

#endif
