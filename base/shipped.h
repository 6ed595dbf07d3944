#pragma once
// The shipped files every tool defaults to, relative to the data folder (the
// repository, or an install's share/vtloc): the CLI (apps/vtloc/shipped.cpp
// finds the folder) and vtloc-bench measure the same default model.
namespace vtloc {

inline constexpr const char* kDefaultModel = "models/vtloc-lite.safetensors";
// The untrained export kept as a fixture (tests, the mug examples): the CLI says
// RANDOM WEIGHTS whenever it runs it.
inline constexpr const char* kRandomModel = "models/vtloc-r18-half-random.safetensors";

}  // namespace vtloc
