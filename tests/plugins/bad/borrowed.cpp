// Exports no plugin symbols of its own but depends on a library that does (dlsym on this
// library would find them there): it must not be taken for that plugin.
extern "C" int kg_bad_base_marker();

extern "C" __attribute__((visibility("default"))) int kg_bad_borrowed_marker() {
  return kg_bad_base_marker();
}
