/* hostcheck_rng.h — the xorshift generator the follower and LOD host checks draw their cases
 * from (host code only; the same sequence for a seed on every machine). */
#ifndef HB_HOSTCHECK_RNG_H
#define HB_HOSTCHECK_RNG_H

#include <stdint.h>

struct Rng {
    uint64_t s;
    double u()
    {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        return (double)(s >> 11) * (1.0 / 9007199254740992.0);
    }
    double sym() { return 2.0 * u() - 1.0; }
};

#endif
