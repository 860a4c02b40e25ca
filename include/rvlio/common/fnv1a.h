#pragma once
// FNV-1a, 64 bit: the project's one content hash (refine checkpoints, the
// ablation cells' identities, the tests' simulation cache). Not
// cryptographic: it tells inputs apart, it does not authenticate them.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace rvlio {

class Fnv1a {
 public:
  // The bytes of a trivially copyable value (pass values, not padded structs).
  template <class T>
  void Add(const T& value) {
    AddBytes(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void AddBytes(const char* bytes, size_t n) {
    for (size_t i = 0; i < n; ++i)
      hash_ = (hash_ ^ static_cast<unsigned char>(bytes[i])) * 0x100000001b3ULL;
  }
  // A string's length, then its bytes (so "ab"+"c" differs from "a"+"bc").
  void AddText(std::string_view text) {
    Add(text.size());
    AddBytes(text.data(), text.size());
  }
  uint64_t value() const { return hash_; }

 private:
  uint64_t hash_ = 0xcbf29ce484222325ULL;
};

// The hash of `bytes` (no length prefix) as 16 lower-case hex digits.
inline std::string Fnv1aHex(std::string_view bytes) {
  Fnv1a h;
  h.AddBytes(bytes.data(), bytes.size());
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(h.value()));
  return hex;
}

}  // namespace rvlio
