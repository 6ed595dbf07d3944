// Linked into the sanitizer builds of the tests only (tests/CMakeLists.txt).
// LSan can name a leak's module only while that module is mapped, and the
// Vulkan loader unloads the driver and layers at every vkDestroyInstance: a
// leak inside Mesa would show as "<unknown module>" and could not be told
// from ours or suppressed by name. Keeping every dlopen'ed module loaded until
// exit (dlclose does nothing) leaves them mapped; the loader still works, it
// just finds the module already there on the next vkCreateInstance.
extern "C" int dlclose(void*) { return 0; }
