// Whether the tests run in the AddressSanitizer build (scripts/test.sh's second pass).
#pragma once

namespace kozu::test {

// Whether this build runs under AddressSanitizer (its shadow memory rules out address-space limits).
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

}  // namespace kozu::test
