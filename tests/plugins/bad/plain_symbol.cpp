// Exports kg_plugin_abi_version as a plain C function rather than a Boost.DLL alias (a pointer to
// the function): reading it as an alias would jump into the function's code bytes.
#include <cstdint>

extern "C" __attribute__((visibility("default"))) std::uint32_t kg_plugin_abi_version() {
  return 1;
}
