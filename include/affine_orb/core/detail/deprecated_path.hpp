#pragma once
/// \file
/// AFFINE_ORB_DEPRECATED_PATH("message"): a compiler warning with the message where a header is
/// included (GCC and Clang: #pragma GCC warning; MSVC: #pragma message; nothing elsewhere). The
/// headers at the include paths of 0.1 (affine_orb/fast.hpp, ...) use it to say where each header
/// lives since 0.2.

#if defined(__GNUC__) || defined(__clang__)
#define AFFINE_ORB_DETAIL_PRAGMA(text) _Pragma(#text)
#define AFFINE_ORB_DEPRECATED_PATH(message) AFFINE_ORB_DETAIL_PRAGMA(GCC warning message)
#elif defined(_MSC_VER)
#define AFFINE_ORB_DEPRECATED_PATH(message) __pragma(message(message))
#else
#define AFFINE_ORB_DEPRECATED_PATH(message)
#endif
