// kws_probe: development probe. Decodes raw 16 kHz s16le segments (file names on stdin) with
// the en-us n-gram LM under the given PocketSphinx arguments and prints, per file, the
// hypothesis and the lattice posterior of a word (-word W, default help; -segs also prints the
// best path's segments). Used to choose the LM verification settings.
#include <pocketsphinx.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  const std::string model = "/usr/share/pocketsphinx/model/en-us";
  std::vector<std::string> args = {"-hmm",   model + "/en-us",
                                   "-dict",  model + "/cmudict-en-us.dict",
                                   "-lm",    model + "/en-us.lm.bin",
                                   "-logfn", "/dev/null",
                                   "-cmn",   "current"};
  std::string word = "help";
  bool print_segments = false;    // -segs: every segment of the best path with its frames
  for (int i = 1; i < argc; ++i)  // another search instead of the n-gram LM
    if (std::string(argv[i]) == "-jsgf" || std::string(argv[i]) == "-kws" ||
        std::string(argv[i]) == "-lm")
      args.erase(args.begin() + 4, args.begin() + 6);
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "-word" && i + 1 < argc) {
      word = argv[++i];
      continue;
    }
    if (std::string(argv[i]) == "-segs") {
      print_segments = true;
      continue;
    }
    args.push_back(argv[i]);
  }
  std::vector<char*> av;
  for (auto& a : args) av.push_back(&a[0]);
  cmd_ln_t* config =
      cmd_ln_parse_r(nullptr, ps_args(), static_cast<int32>(av.size()), av.data(), TRUE);
  ps_decoder_t* ps = ps_init(config);
  if (!ps) return 1;
  logmath_t* lmath = ps_get_logmath(ps);
  std::string file;
  while (std::getline(std::cin, file)) {
    std::ifstream in(file, std::ios::binary);
    std::vector<int16_t> s((std::istreambuf_iterator<char>(in)), {});
    std::vector<int16_t> x(s.size() / 2);
    in.close();
    std::ifstream in2(file, std::ios::binary);
    in2.read(reinterpret_cast<char*>(x.data()), x.size() * 2);
    ps_start_utt(ps);
    ps_process_raw(ps, x.data(), x.size(), FALSE, TRUE);
    ps_end_utt(ps);
    int32 score = 0;
    const char* hyp = ps_get_hyp(ps, &score);
    double best = 0, best_1 = 0;
    for (ps_seg_t* seg = ps_seg_iter(ps); seg; seg = ps_seg_next(seg)) {
      std::string w = ps_seg_word(seg);
      const size_t paren = w.find('(');
      if (paren != std::string::npos) w = w.substr(0, paren);
      int32 a, l, b;
      if (print_segments) {
        int sf, ef;
        ps_seg_frames(seg, &sf, &ef);
        std::printf("  seg %s %d-%d prob %d\n", w.c_str(), sf, ef, ps_seg_prob(seg, &a, &l, &b));
      }
      if (w == word) best_1 = std::max(best_1, logmath_exp(lmath, ps_seg_prob(seg, &a, &l, &b)));
    }
    if (ps_lattice_t* dag = ps_get_lattice(ps)) {
      for (ps_latnode_iter_t* it = ps_latnode_iter(dag); it; it = ps_latnode_iter_next(it)) {
        ps_latnode_t* node = ps_latnode_iter_node(it);
        const char* base = ps_latnode_baseword(dag, node);
        if (!base || word != base) continue;
        ps_latlink_t* bl = nullptr;
        best = std::max(best, logmath_exp(lmath, ps_latnode_prob(dag, node, &bl)));
      }
    }
    std::printf("%s\t%.4f\t%.4f\t%s\n", file.c_str(), best_1, std::min(1.0, best), hyp ? hyp : "");
    std::fflush(stdout);
  }
  ps_free(ps);
  cmd_ln_free_r(config);
  return 0;
}
