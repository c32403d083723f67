// The attributes of a kernel written once over the lane sets (pair_kernel_wide.h,
// integrate_wide.h): each width's file defines DEMLAB_WIDE_TARGET, the target string of its
// lane set ("avx2", or "avx2,avx512f,avx512dq,avx512vl"), and includes the kernel after it,
// so that the kernel's functions are compiled for that target and the lane helpers inline
// into them.
#pragma once

#ifndef DEMLAB_WIDE_TARGET
#error "define DEMLAB_WIDE_TARGET (the target string of the including file's width) first"
#endif
#define DEMLAB_WIDE [[gnu::target(DEMLAB_WIDE_TARGET), gnu::always_inline]] static inline
#define DEMLAB_WIDE_LAMBDA __attribute__((target(DEMLAB_WIDE_TARGET), always_inline))
