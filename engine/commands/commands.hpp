// The subcommands of the lodforge binary, registered in one explicit list in cli/main.cpp.
#pragma once

namespace lodforge {

int run_synth(int argc, char** argv);
int run_regularize(int argc, char** argv);
int run_options(int argc, char** argv);
int run_job(int argc, char** argv);
int run_config(int argc, char** argv);
int run_merge(int argc, char** argv);
int run_eval(int argc, char** argv);

}  // namespace lodforge
