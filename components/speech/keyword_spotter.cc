#include "speech/keyword_spotter.h"

#include <pocketsphinx.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

#include "speech/hit_features.h"
#include "speech/verification_vocabulary.h"

namespace sarmap {
namespace speech {
namespace {

// Whether every word of `phrase` is among the decoded `words`, and the lowest posterior among
// them (a phrase is only as certain as its least certain word).
bool PhraseConfidence(const std::string& phrase, const std::vector<std::pair<std::string, double>>& words,
                      double* confidence) {
  std::istringstream ws(phrase);
  std::string w;
  double conf = 1.0;
  while (ws >> w) {
    double best = -1;
    for (const auto& [word, post] : words) {
      if (word == w) best = std::max(best, post);
    }
    if (best < 0) return false;
    conf = std::min(conf, best);
  }
  *confidence = conf;
  return true;
}

}  // namespace

struct KeywordSpotter::Impl {
  ps_decoder_t* ps = nullptr;
  cmd_ln_t* config = nullptr;
  std::string kws_file;
  int64_t kws_samples = 0;  // samples given to the decoder so far (any search)
  bool can_verify = false;
  ~Impl() {
    if (ps) ps_free(ps);
    if (config) cmd_ln_free_r(config);
    if (!kws_file.empty()) std::remove(kws_file.c_str());
  }
};

KeywordSpotter::KeywordSpotter(const KeywordOptions& options)
    : options_(options), verifier_(options.verifier), impl_(new Impl) {
  namespace fs = std::filesystem;
  const std::string hmm = options.model_dir + "/en-us";
  const std::string lm = options.model_dir + "/en-us.lm.bin";
  const std::string dict = options.model_dir + "/cmudict-en-us.dict";
  for (const auto& p : {hmm, lm, dict})
    if (!fs::exists(p)) throw std::runtime_error("PocketSphinx model missing: " + p + " (install pocketsphinx-en-us)");
  // The n-gram model is large and slow to load: only with full decoding or LM verification.
  // -allphone_ci: the verification phone loop uses context-independent phones (the
  // triphone loop with the phonetic LM costs ~50x more).
  std::vector<std::string> args = {"-hmm", hmm,     "-dict",        dict, "-logfn", "/dev/null",
                                   "-cmn", options.cmn, "-allphone_ci", "yes"};
  if (options.full_decoding || options.verify_with_lm) {
    args.insert(args.end(), {"-lm", lm});
    // No second (flat-lexicon) pass and bounded active HMMs/words per frame: several times
    // faster than the defaults.
    args.insert(args.end(), {"-fwdflat", "no", "-maxhmmpf", "3000", "-maxwpf", "10"});
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(&a[0]);
  impl_->config = cmd_ln_parse_r(nullptr, ps_args(), static_cast<int32>(argv.size()), argv.data(), TRUE);
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
  // Verification searches: one forced grammar per keyphrase and the phone loop.
  const std::string phone_lm = options.model_dir + "/en-us-phone.lm.bin";
  if (fs::exists(phone_lm)) {
    if (ps_set_allphone_file(impl_->ps, "allphone", options.verify_phone_lm ? phone_lm.c_str() : nullptr) < 0)
      throw std::runtime_error("PocketSphinx: cannot set the phone loop from " + phone_lm);
    for (size_t i = 0; i < options.keywords.size(); ++i) {
      const std::string jsgf = "#JSGF V1.0;\ngrammar align;\npublic <k> = " + options.keywords[i] + ";\n";
      if (ps_set_jsgf_string(impl_->ps, ("align_" + std::to_string(i)).c_str(), jsgf.c_str()) < 0)
        throw std::runtime_error("PocketSphinx: cannot build the alignment grammar of '" + options.keywords[i] + "'");
    }
    impl_->can_verify = true;
  } else if (options.verify_acoustic || (options.verifier.enabled && NeedsPhoneLoop(options.verifier))) {
    throw std::runtime_error("PocketSphinx phonetic LM missing: " + phone_lm + " (needed by verify_acoustic)");
  }
  ps_set_search(impl_->ps, "kws");
  if (options.verify_with_grammar) {
    // A free loop over a general vocabulary plus the keywords: the keyword must win against
    // every other word there, its sound-alikes included.
    std::set<std::string> vocab;
    std::istringstream vs(kVerificationVocabulary);
    std::string w;
    while (vs >> w) vocab.insert(w);
    for (const auto& k : options.keywords) {
      std::istringstream ks(k);
      while (ks >> w) vocab.insert(w);
    }
    std::string alternatives;
    for (const auto& v : vocab) {
      char* pron = ps_lookup_word(impl_->ps, v.c_str());
      if (!pron) continue;
      ckd_free(pron);
      alternatives += (alternatives.empty() ? "" : " | ") + v;
    }
    const std::string jsgf = "#JSGF V1.0;\ngrammar verify;\npublic <utt> = <w>+;\n<w> = " + alternatives + ";\n";
    if (ps_set_jsgf_string(impl_->ps, "verify", jsgf.c_str()) < 0)
      throw std::runtime_error("PocketSphinx: cannot build the verification grammar");
  }
}

KeywordSpotter::~KeywordSpotter() = default;

HitFeatures KeywordSpotter::Features(const int16_t* samples, size_t count, const KeywordHit& h, double onset_s,
                                     double end_s, bool with_phones) {
  const double utterance_s = static_cast<double>(count) / 16000.0;
  HitFeatures f = ComputeHitFeatures(samples, count, onset_s < 0 ? 0.0 : onset_s, end_s < 0 ? utterance_s : end_s,
                                     h.start_s, h.end_s, h.log_ratio);
  if (with_phones) {
    // The phone loop over the hit widened by 0.1 s, against the keyword's dictionary phones.
    const size_t a = static_cast<size_t>(std::max(0.0, h.start_s - 0.1) * 16000);
    const size_t b = std::min(count, static_cast<size_t>((h.end_s + 0.1) * 16000));
    const auto phones = b > a ? PhoneLoop(samples + a, b - a) : std::vector<std::string>{};
    const auto want = KeywordPhones(h.keyword);
    for (const auto& p : phones) f.phones += (f.phones.empty() ? "" : " ") + p;
    f.phone_distance = want.empty() ? -1.0 : static_cast<double>(PhoneEditDistance(phones, want)) / want.size();
  }
  return f;
}

DecodeResult KeywordSpotter::Decode(const int16_t* samples, size_t count, bool full, double speech_onset_s,
                                    double speech_end_s) {
  DecodeResult r;
  // A call is a short utterance: longer ones cannot hold one, and are not decoded at all
  // (unless the full text is wanted).
  if (options_.max_utterance_s > 0 && !full && !compute_verification_ &&
      static_cast<double>(count) / 16000.0 > options_.max_utterance_s)
    return r;
  ps_decoder_t* ps = impl_->ps;
  logmath_t* lmath = ps_get_logmath(ps);
  ps_set_search(ps, "kws");
  // The kws search numbers frames from the decoder's start (across all searches), not the
  // utterance's.
  const double offset_s = static_cast<double>(impl_->kws_samples) / 16000.0;
  impl_->kws_samples += count;
  ps_start_utt(ps);
  ps_process_raw(ps, samples, count, FALSE, options_.full_utterance ? TRUE : FALSE);
  ps_end_utt(ps);
  const int frame_rate = cmd_ln_int32_r(impl_->config, "-frate");
  for (ps_seg_t* seg = ps_seg_iter(ps); seg; seg = ps_seg_next(seg)) {
    KeywordHit h;
    h.keyword = ps_seg_word(seg);
    while (!h.keyword.empty() && h.keyword.back() == ' ') h.keyword.pop_back();  // kws pads words
    int sf = 0, ef = 0;
    ps_seg_frames(seg, &sf, &ef);
    h.start_s = std::max(0.0, static_cast<double>(sf) / frame_rate - offset_s);
    h.end_s = std::max(0.0, static_cast<double>(ef) / frame_rate - offset_s);
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
    h.kws_confidence = h.confidence;
    r.keywords.push_back(h);
  }
  // The kws search may fire several times on one spoken keyword (a low threshold): merge
  // detections of the same keyword that overlap or nearly touch, keeping the strongest.
  std::sort(r.keywords.begin(), r.keywords.end(), [](const KeywordHit& a, const KeywordHit& b) {
    return a.start_s < b.start_s;
  });
  std::vector<KeywordHit> merged;
  for (const KeywordHit& h : r.keywords) {
    bool joined = false;
    for (KeywordHit& m : merged)
      if (m.keyword == h.keyword && h.start_s < m.end_s + 0.3) {
        m.end_s = std::max(m.end_s, h.end_s);
        if (h.log_ratio > m.log_ratio) {
          m.log_ratio = h.log_ratio;
          m.confidence = h.confidence;
          m.kws_confidence = h.kws_confidence;
        }
        joined = true;
      }
    if (!joined) merged.push_back(h);
  }
  // Keyphrases sharing a word ("help", "help me") fire together on one call: of overlapping
  // detections that share a word keep the longest phrase (the more specific one).
  auto words_of = [](const std::string& k) {
    std::set<std::string> w;
    std::istringstream ws(k);
    std::string x;
    while (ws >> x) w.insert(x);
    return w;
  };
  std::vector<bool> dropped(merged.size(), false);
  for (size_t i = 0; i < merged.size(); ++i)
    for (size_t j = 0; j < merged.size(); ++j) {
      if (i == j || dropped[j] || merged[i].keyword == merged[j].keyword) continue;
      const KeywordHit& a = merged[i];
      const KeywordHit& b = merged[j];
      if (a.end_s < b.start_s || b.end_s < a.start_s) continue;
      const auto wa = words_of(a.keyword), wb = words_of(b.keyword);
      bool share = false;
      for (const auto& w : wa) share |= wb.count(w) > 0;
      if (share && (wa.size() < wb.size() || (wa.size() == wb.size() && a.log_ratio < b.log_ratio))) {
        dropped[i] = true;
        break;
      }
    }
  r.keywords.clear();
  for (size_t i = 0; i < merged.size(); ++i)
    if (!dropped[i]) r.keywords.push_back(merged[i]);
  const double utterance_s = static_cast<double>(count) / 16000.0;
  for (KeywordHit& h : r.keywords) h.utterance_s = utterance_s;
  if (options_.verify_acoustic || options_.min_duration_s > 0 || options_.max_duration_s < 10 ||
      options_.min_utterance_fraction > 0 || options_.max_utterance_s > 0 || compute_verification_ ||
      options_.verifier.enabled) {
    std::vector<KeywordHit> kept;
    for (KeywordHit h : r.keywords) {
      const double duration_s = h.end_s - h.start_s;
      const bool shape_ok = duration_s >= options_.min_duration_s && duration_s <= options_.max_duration_s &&
                            duration_s >= options_.min_utterance_fraction * utterance_s &&
                            (options_.max_utterance_s <= 0 || utterance_s <= options_.max_utterance_s);
      if ((options_.verify_acoustic && shape_ok) || compute_verification_) {
        const size_t a = static_cast<size_t>(std::max(0.0, h.start_s - options_.verify_pad_s) * 16000);
        const size_t b = std::min(count, static_cast<size_t>((h.end_s + options_.verify_pad_s) * 16000));
        h.verify_llr = b > a ? VerificationLlr(h.keyword, samples + a, b - a) : -HUGE_VAL;
        h.verified = true;
      }
      if (!shape_ok) continue;
      if (options_.verify_acoustic && h.verify_llr < options_.verify_min_llr) continue;
      if (verifier_.options().enabled) {
        h.features = Features(samples, count, h, speech_onset_s, speech_end_s, NeedsPhoneLoop(verifier_.options()));
        h.verifier_probability = verifier_.Probability(h.features);
        if (h.verifier_probability < verifier_.options().min_probability) continue;
      }
      if (options_.verify_acoustic) {
        // Confidence from the verification margin: 0.5 at the threshold, 0.9 at +0.2 nats/frame.
        const double margin = h.verify_llr - options_.verify_min_llr;
        h.confidence = 1.0 / (1.0 + std::exp(-margin * std::log(9.0) / 0.2));
      }
      kept.push_back(h);
    }
    r.keywords = kept;
  }
  if (options_.verify_with_grammar && !r.keywords.empty()) {
    const auto words = DecodeSearch("verify", samples, count);
    std::vector<KeywordHit> kept;
    for (KeywordHit h : r.keywords) {
      double conf;
      if (!PhraseConfidence(h.keyword, words, &conf)) continue;
      h.confidence = std::min(h.kws_confidence, conf);
      kept.push_back(h);
    }
    r.keywords = kept;
  }
  if (full || (options_.verify_with_lm && !r.keywords.empty())) {
    const auto words = DecodeWords(samples, count, &r.text, &r.text_confidence);
    if (options_.verify_with_lm) {
      std::vector<KeywordHit> kept;
      for (KeywordHit h : r.keywords) {
        // Every word of the keyphrase must be in the LM hypothesis.
        double conf;
        if (!PhraseConfidence(h.keyword, words, &conf)) continue;
        h.confidence = conf;
        kept.push_back(h);
      }
      r.keywords = kept;
    }
    if (!full) r.text.clear();
  }
  return r;
}

double KeywordSpotter::VerificationLlr(const std::string& keyword, const int16_t* samples, size_t count) {
  if (!impl_->can_verify) throw std::logic_error("acoustic verification needs en-us-phone.lm.bin");
  size_t idx = 0;
  while (idx < options_.keywords.size() && options_.keywords[idx] != keyword) ++idx;
  if (idx == options_.keywords.size()) throw std::invalid_argument("not a keyword: " + keyword);
  ps_decoder_t* ps = impl_->ps;
  // Sum of the acoustic scores along the best path of a search over the segment; *ok false
  // when the search finds no path. (Same front-end mode as the kws pass: mixing batch and live
  // utterances trips an assertion in PocketSphinx 5prealpha's acmod.)
  auto acoustic = [&](const std::string& search, bool* ok) {
    ps_set_search(ps, search.c_str());
    impl_->kws_samples += count;
    ps_start_utt(ps);
    ps_process_raw(ps, samples, count, FALSE, options_.full_utterance ? TRUE : FALSE);
    ps_end_utt(ps);
    int64_t sum = 0;
    int segments = 0;
    for (ps_seg_t* seg = ps_seg_iter(ps); seg; seg = ps_seg_next(seg)) {
      int32 a = 0, l = 0, b = 0;
      ps_seg_prob(seg, &a, &l, &b);
      sum += a;
      ++segments;
    }
    *ok = segments > 0;
    return sum;
  };
  bool ok_forced = false, ok_free = false;
  const int64_t forced = acoustic("align_" + std::to_string(idx), &ok_forced);
  const int64_t free = acoustic("allphone", &ok_free);
  ps_set_search(ps, "kws");
  if (!ok_forced || !ok_free) return -HUGE_VAL;
  const double frames = std::max(1.0, static_cast<double>(count) / 160.0);
  logmath_t* lmath = ps_get_logmath(ps);
  return (logmath_log_to_ln(lmath, static_cast<int>(forced - free))) / frames;
}

std::vector<std::string> KeywordSpotter::PhoneLoop(const int16_t* samples, size_t count) {
  if (!impl_->can_verify) throw std::logic_error("the phone loop needs en-us-phone.lm.bin");
  ps_decoder_t* ps = impl_->ps;
  ps_set_search(ps, "allphone");
  impl_->kws_samples += count;
  ps_start_utt(ps);
  ps_process_raw(ps, samples, count, FALSE, options_.full_utterance ? TRUE : FALSE);
  ps_end_utt(ps);
  std::vector<std::string> phones;
  for (ps_seg_t* seg = ps_seg_iter(ps); seg; seg = ps_seg_next(seg)) {
    const std::string p = ps_seg_word(seg);
    if (p.empty() || p == "SIL" || p[0] == '+' || p[0] == '<' || p[0] == '[') continue;
    phones.push_back(p);
  }
  ps_set_search(ps, "kws");
  return phones;
}

std::vector<std::string> KeywordSpotter::KeywordPhones(const std::string& keyword) {
  std::vector<std::string> phones;
  std::istringstream words(keyword);
  std::string w;
  while (words >> w) {
    char* pron = ps_lookup_word(impl_->ps, w.c_str());
    if (!pron) throw std::invalid_argument("word '" + w + "' is not in the dictionary");
    std::istringstream ps(pron);
    std::string p;
    while (ps >> p) phones.push_back(p);
    ckd_free(pron);
  }
  return phones;
}

std::vector<std::pair<std::string, double>> KeywordSpotter::DecodeSearch(const std::string& search,
                                                                         const int16_t* samples, size_t count) {
  ps_decoder_t* ps = impl_->ps;
  ps_set_search(ps, search.c_str());
  impl_->kws_samples += count;
  ps_start_utt(ps);
  ps_process_raw(ps, samples, count, FALSE, options_.full_utterance ? TRUE : FALSE);
  ps_end_utt(ps);
  logmath_t* lmath = ps_get_logmath(ps);
  std::vector<std::pair<std::string, double>> words;
  for (ps_seg_t* seg = ps_seg_iter(ps); seg; seg = ps_seg_next(seg)) {
    std::string w = ps_seg_word(seg);
    const size_t paren = w.find('(');
    if (paren != std::string::npos) w = w.substr(0, paren);
    if (w.empty() || w[0] == '<' || w[0] == '[') continue;
    int32 a = 0, l = 0, b = 0;
    words.emplace_back(w, std::min(1.0, logmath_exp(lmath, ps_seg_prob(seg, &a, &l, &b))));
  }
  ps_set_search(ps, "kws");
  return words;
}

std::vector<std::pair<std::string, double>> KeywordSpotter::DecodeWords(const int16_t* samples, size_t count,
                                                                        std::string* text, double* confidence) {
  if (!options_.full_decoding && !options_.verify_with_lm)
    throw std::logic_error("language-model decoding needs full_decoding or verify_with_lm");
  ps_decoder_t* ps = impl_->ps;
  ps_set_search(ps, "_default");  // the -lm search
  impl_->kws_samples += count;
  ps_start_utt(ps);
  ps_process_raw(ps, samples, count, FALSE, options_.full_utterance ? TRUE : FALSE);
  ps_end_utt(ps);
  int32 score = 0;
  const char* hyp = ps_get_hyp(ps, &score);
  *text = hyp ? hyp : "";
  logmath_t* lmath = ps_get_logmath(ps);
  *confidence = logmath_exp(lmath, ps_get_prob(ps));
  std::vector<std::pair<std::string, double>> words;
  for (ps_seg_t* seg = ps_seg_iter(ps); seg; seg = ps_seg_next(seg)) {
    std::string w = ps_seg_word(seg);
    const size_t paren = w.find('(');  // alternate pronunciations: help(2)
    if (paren != std::string::npos) w = w.substr(0, paren);
    if (w.empty() || w[0] == '<' || w[0] == '[') continue;  // <s>, </s>, <sil>, [NOISE]
    int32 a = 0, l = 0, b = 0;
    words.emplace_back(w, logmath_exp(lmath, ps_seg_prob(seg, &a, &l, &b)));
  }
  // Every word of the lattice with its posterior probability: a keyword that lost the 1-best
  // path narrowly still counts, with its (lower) posterior as the confidence.
  if (ps_lattice_t* dag = ps_get_lattice(ps)) {
    for (ps_latnode_iter_t* it = ps_latnode_iter(dag); it; it = ps_latnode_iter_next(it)) {
      ps_latnode_t* node = ps_latnode_iter_node(it);
      const char* base = ps_latnode_baseword(dag, node);
      if (!base || base[0] == '<' || base[0] == '[') continue;
      ps_latlink_t* best = nullptr;
      const int32 post = ps_latnode_prob(dag, node, &best);
      words.emplace_back(base, std::min(1.0, logmath_exp(lmath, post)));
    }
  }
  ps_set_search(ps, "kws");
  return words;
}

std::string KeywordSpotter::DecodeText(const std::vector<int16_t>& samples, double* confidence) {
  std::string text;
  double conf = 0;
  DecodeWords(samples.data(), samples.size(), &text, &conf);
  if (confidence) *confidence = conf;
  return text;
}

}  // namespace speech
}  // namespace sarmap
