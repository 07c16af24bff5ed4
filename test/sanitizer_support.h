// Whether this test program was built with a sanitizer that brings its own allocator (AddressSanitizer,
// ThreadSanitizer; GCC's and clang's macros): glibc's heap statistics (mallinfo2) do not see that allocator.
#pragma once

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define RC_SANITIZER_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define RC_SANITIZER_ALLOCATOR 1
#endif
#endif
