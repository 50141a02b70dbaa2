// The `nestlight` command line: one program, sub-commands as in git and PDAL.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace nestlight::cli {

// Each adds its sub-command; the callback stores the exit code in `exitCode`.
void addConvert(CLI::App& app, int& exitCode);
void addInfo(CLI::App& app, int& exitCode);
void addVerify(CLI::App& app, int& exitCode);
void addExport(CLI::App& app, int& exitCode);
void addGenerate(CLI::App& app, int& exitCode);
void addDemo(CLI::App& app, int& exitCode);
void addBench(CLI::App& app, int& exitCode);
void addStress(CLI::App& app, int& exitCode);

// "1G", "512M", "64k", plain bytes.
uint64_t parseBytes(const std::string& text);
// Files as given; a directory stands for its supported point files, sorted by name.
std::vector<std::string> expandInputs(const std::vector<std::string>& inputs);
std::string humanBytes(double bytes);
std::string humanCount(double n);

}  // namespace nestlight::cli
