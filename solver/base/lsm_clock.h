/* lsm_clock: seconds on a monotonic clock, for the timings in run.json, progress and the
 * backends' facts (differences only: the origin is arbitrary). */
#ifndef LSM_CLOCK_H
#define LSM_CLOCK_H

double lsm_clock_seconds(void);

#endif
