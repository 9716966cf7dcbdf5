// accelcal: the command-line tool (cli.cpp).
#include "commands.hpp"

int main(int argc, char** argv) { return accelcal::cli::RunCommandLine(argc, argv); }
