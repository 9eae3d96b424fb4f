// sarmap-log output LOG: what every process printed while it ran under the launcher, from the
// deputies' PM_OUTPUT messages in the log, one file per command (or one command to stdout).
// Deputies sign PM_OUTPUT with the launcher's key: with --key only output whose signature holds
// is kept (a forged deputy's or command's output, or forged lines of a real command, are
// skipped).
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <utility>

#include "common/args.h"
#include "common/decode.h"
#include "log-tools/lcm_log_reader.h"
#include "procman/order_auth.h"
#include "sarmap/pm_output_t.hpp"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log output", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log output",
        "Writes what every process printed while it ran under sarmap-procman, from the deputies'\n"
        "PM_OUTPUT messages recorded in the log: DIR/DEPUTY-COMMAND.txt per command, or one\n"
        "command's output to stdout with --command.");
    std::string log, dir, command, channel = "PM_OUTPUT";
    parser.AddPositional("LOG", &log, "LCM log recorded while the stack ran under sarmap-procman");
    parser.AddFlag("-o", &dir, "output directory (one file per deputy and command)");
    parser.AddFlag("--command", &command, "print only this command's output to stdout");
    parser.AddFlag("--channel", &channel, "channel of the deputies' output");
    std::string key_path;
    parser.AddFlag("--key", &key_path,
                   "the launcher's key file: only output signed with it is kept");
    if (!parser.Parse(argc, argv)) return 0;
    if (dir.empty() && command.empty())
      throw sarmap::common::ArgError("give -o DIR or --command NAME");
    std::optional<sarmap::procman::Key> key;
    if (!key_path.empty()) key = sarmap::procman::LoadKeyFile(key_path);

    if (!dir.empty()) std::filesystem::create_directories(dir);
    sarmap::logtools::LcmLogReader reader(log);
    sarmap::logtools::LogEvent event;
    std::map<std::string, std::unique_ptr<std::ofstream>> files;
    int64_t messages = 0, bad = 0, unsigned_messages = 0;
    while (reader.Next(&event)) {
      if (event.channel != channel) continue;
      sarmap::pm_output_t out;
      if (!sarmap::common::DecodeMessage(event.data.data(), event.data.size(), &out)) {
        ++bad;
        continue;
      }
      if (key && !sarmap::procman::SignatureValid(*key, out)) {
        ++unsigned_messages;
        continue;
      }
      ++messages;
      for (size_t i = 0; i < out.command_ids.size(); ++i) {
        if (!command.empty()) {
          if (out.command_ids[i] == command) fputs(out.text[i].c_str(), stdout);
          continue;
        }
        // Command ids are names from the launch file; keep file names plain and short (without
        // --key the message may come from anyone: names may hold anything).
        std::string name = out.deputy_id + "-" + out.command_ids[i];
        for (char& c : name) {
          const unsigned char u = static_cast<unsigned char>(c);
          if (!(std::isalnum(u) || c == '-' || c == '.' || c == '[' || c == ']' || c == '+'))
            c = '_';
        }
        if (name.size() > 120) name.resize(120);
        auto& file = files[name];
        if (!file) {
          file = std::make_unique<std::ofstream>(dir + "/" + name + ".txt");
          if (!*file) throw std::runtime_error("cannot write " + dir + "/" + name + ".txt");
        }
        *file << out.text[i];
      }
    }
    if (unsigned_messages > 0) {
      fprintf(stderr, "%lld unsigned or forged output messages skipped\n",
              static_cast<long long>(unsigned_messages));
    }
    if (bad > 0)
      fprintf(stderr, "warning: %lld undecodable %s messages skipped\n",
              static_cast<long long>(bad), channel.c_str());
    if (!dir.empty()) {
      fprintf(stderr, "%lld output messages; %zu files in %s\n", static_cast<long long>(messages),
              files.size(), dir.c_str());
    }
    return 0;
  });
}
