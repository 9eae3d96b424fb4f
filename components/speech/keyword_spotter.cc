#include "speech/keyword_spotter.h"

#include <pocketsphinx.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

namespace sarmap {
namespace speech {

struct KeywordSpotter::Impl {
  ps_decoder_t* ps = nullptr;
  cmd_ln_t* config = nullptr;
  std::string kws_file;
  ~Impl() {
    if (ps) ps_free(ps);
    if (config) cmd_ln_free_r(config);
    if (!kws_file.empty()) std::remove(kws_file.c_str());
  }
};

KeywordSpotter::KeywordSpotter(const KeywordOptions& options) : options_(options), impl_(new Impl) {
  namespace fs = std::filesystem;
  const std::string hmm = options.model_dir + "/en-us";
  const std::string lm = options.model_dir + "/en-us.lm.bin";
  const std::string dict = options.model_dir + "/cmudict-en-us.dict";
  for (const auto& p : {hmm, lm, dict})
    if (!fs::exists(p)) throw std::runtime_error("PocketSphinx model missing: " + p + " (install pocketsphinx-en-us)");
  // The n-gram model is large and slow to load: only with full decoding.
  if (options.full_decoding)
    impl_->config = cmd_ln_init(nullptr, ps_args(), TRUE, "-hmm", hmm.c_str(), "-lm", lm.c_str(), "-dict",
                                dict.c_str(), "-logfn", "/dev/null", nullptr);
  else
    impl_->config = cmd_ln_init(nullptr, ps_args(), TRUE, "-hmm", hmm.c_str(), "-dict", dict.c_str(), "-logfn",
                                "/dev/null", nullptr);
  if (!impl_->config) throw std::runtime_error("PocketSphinx: bad configuration");
  impl_->ps = ps_init(impl_->config);
  if (!impl_->ps) throw std::runtime_error("PocketSphinx: cannot initialise the decoder with " + options.model_dir);
  // Keyword list file: "phrase /threshold/" per line.
  std::ostringstream kws;
  for (size_t i = 0; i < options.keywords.size(); ++i) {
    const double t = options.thresholds.size() == 1 ? options.thresholds[0] : options.thresholds[i];
    std::istringstream words(options.keywords[i]);
    std::string w;
    while (words >> w) {
      char* pron = ps_lookup_word(impl_->ps, w.c_str());
      if (!pron) throw std::runtime_error("keyword '" + options.keywords[i] + "': word '" + w + "' is not in " + dict);
      ckd_free(pron);
    }
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%g", t);
    kws << options.keywords[i] << " /" << buf << "/\n";
  }
  impl_->kws_file = (fs::temp_directory_path() / ("sarmap_kws_" + std::to_string(::getpid()) + "_" +
                                                  std::to_string(reinterpret_cast<uintptr_t>(this)) + ".kws")).string();
  std::ofstream(impl_->kws_file) << kws.str();
  if (ps_set_kws(impl_->ps, "kws", impl_->kws_file.c_str()) < 0)
    throw std::runtime_error("PocketSphinx: cannot set the keyword list");
}

KeywordSpotter::~KeywordSpotter() = default;

DecodeResult KeywordSpotter::Decode(const int16_t* samples, size_t count, bool full) {
  DecodeResult r;
  ps_decoder_t* ps = impl_->ps;
  logmath_t* lmath = ps_get_logmath(ps);
  ps_set_search(ps, "kws");
  ps_start_utt(ps);
  ps_process_raw(ps, samples, count, FALSE, TRUE);
  ps_end_utt(ps);
  const int frame_rate = cmd_ln_int32_r(impl_->config, "-frate");
  for (ps_seg_t* seg = ps_seg_iter(ps); seg; seg = ps_seg_next(seg)) {
    KeywordHit h;
    h.keyword = ps_seg_word(seg);
    while (!h.keyword.empty() && h.keyword.back() == ' ') h.keyword.pop_back();  // kws pads words
    int sf = 0, ef = 0;
    ps_seg_frames(seg, &sf, &ef);
    h.start_s = static_cast<double>(sf) / frame_rate;
    h.end_s = static_cast<double>(ef) / frame_rate;
    int32 ascr = 0, lscr = 0, lback = 0;
    const int32 prob = ps_seg_prob(seg, &ascr, &lscr, &lback);
    h.log_ratio = logmath_log_to_ln(lmath, prob);
    // Confidence: the likelihood ratio against this keyword's threshold, mapped to 0..1 with a
    // logistic in the log domain (0.5 at the threshold, 0.9 at 20 nats above it).
    size_t idx = 0;
    while (idx < options_.keywords.size() && options_.keywords[idx] != h.keyword) ++idx;
    const double thr = options_.thresholds.size() == 1 ? options_.thresholds[0]
                                                       : options_.thresholds[std::min(idx, options_.thresholds.size() - 1)];
    const double margin = h.log_ratio - std::log(thr);
    h.confidence = 1.0 / (1.0 + std::exp(-margin * std::log(9.0) / 20.0));
    r.keywords.push_back(h);
  }
  if (full) r.text = DecodeText(std::vector<int16_t>(samples, samples + count), &r.text_confidence);
  return r;
}

std::string KeywordSpotter::DecodeText(const std::vector<int16_t>& samples, double* confidence) {
  if (!options_.full_decoding)
    throw std::logic_error("full decoding needs KeywordOptions::full_decoding (loads the language model)");
  ps_decoder_t* ps = impl_->ps;
  ps_set_search(ps, "_default");  // the -lm search
  ps_start_utt(ps);
  ps_process_raw(ps, samples.data(), samples.size(), FALSE, TRUE);
  ps_end_utt(ps);
  int32 score = 0;
  const char* hyp = ps_get_hyp(ps, &score);
  if (confidence) *confidence = logmath_exp(ps_get_logmath(ps), ps_get_prob(ps));
  ps_set_search(ps, "kws");
  return hyp ? hyp : "";
}

}  // namespace speech
}  // namespace sarmap
