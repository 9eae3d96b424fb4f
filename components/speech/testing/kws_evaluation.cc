#include "speech/testing/kws_evaluation.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <random>
#include <sstream>

#include "audio_capture/audio_file.h"
#include "common/robot_config.h"
#include "sound_localisation/testing/room_simulation.h"
#include "speech/hit_features.h"

namespace sarmap {
namespace speech {

namespace fs = std::filesystem;

namespace {

// Runs a text-to-speech command line that writes a WAV file and returns its first channel at
// 16 kHz (empty when the command fails). `command` gets the text, kept to characters the shell
// quotes safely, and the WAV path.
std::vector<float> RenderWithCommand(
    const std::string& tool, const std::string& text,
    const std::function<std::string(const std::string& safe_text, const std::string& wav)>&
        command) {
  const std::string path =
      (fs::temp_directory_path() / ("sarmap_" + tool + "_" + std::to_string(::getpid()) + ".wav"))
          .string();
  std::string safe;
  for (char c : text)
    if (std::isalnum(static_cast<unsigned char>(c)) || c == ' ' || c == ',' || c == '.' || c == '!')
      safe += c;
  const std::string cmd = command(safe, path) + " > /dev/null 2>&1";
  if (std::system(cmd.c_str()) != 0) return {};
  auto buf = audio::ReadAudioFile(path);
  fs::remove(path);
  if (buf.channels.empty()) return {};
  return Resample(buf.channels[0], buf.sample_rate_hz, 16000);
}

}  // namespace

bool EspeakAvailable() { return std::system("espeak-ng --version > /dev/null 2>&1") == 0; }

std::vector<float> RenderEspeak(const std::string& text, const std::string& voice, int wpm,
                                int pitch) {
  return RenderWithCommand("espeak", text, [&](const std::string& safe, const std::string& wav) {
    return "espeak-ng -v " + voice + " -s " + std::to_string(wpm) + " -p " + std::to_string(pitch) +
           " -w " + wav + " \"" + safe + "\"";
  });
}

bool FliteAvailable() { return std::system("flite -lv > /dev/null 2>&1") == 0; }

std::vector<float> RenderFlite(const std::string& text, const std::string& voice, double stretch) {
  char stretch_text[32];
  std::snprintf(stretch_text, sizeof(stretch_text), "%.3f", stretch);
  return RenderWithCommand("flite", text, [&](const std::string& safe, const std::string& wav) {
    return "flite -voice " + voice + " --setf duration_stretch=" + stretch_text + " -t \"" + safe +
           "\" -o " + wav;
  });
}

namespace {

const std::vector<std::string> kFliteVoices = {"kal16", "awb", "rms", "slt"};

// Renders with the chosen synthesiser; espeak: voice, words per minute and pitch as given;
// flite: voice index modulo its 4 voices, the rate as a duration stretch (155 wpm = 1).
std::vector<float> Render(const std::string& tts, const std::string& text,
                          const std::string& espeak_voice, size_t voice_index, int wpm, int pitch) {
  if (tts == "flite")
    return RenderFlite(text, kFliteVoices[voice_index % kFliteVoices.size()], 155.0 / wpm);
  return RenderEspeak(text, espeak_voice, wpm, pitch);
}

double Rms(const std::vector<float>& x) {
  double e = 0;
  for (float v : x) e += static_cast<double>(v) * v;
  return std::sqrt(e / std::max<size_t>(1, x.size()));
}

// Active-speech RMS (ignores the silent parts espeak adds).
double ActiveRms(const std::vector<float>& x) {
  const double peak_rms = Rms(x);
  double e = 0;
  size_t n = 0;
  for (size_t i = 0; i + 160 <= x.size(); i += 160) {
    double f = 0;
    for (size_t j = i; j < i + 160; ++j) f += static_cast<double>(x[j]) * x[j];
    if (std::sqrt(f / 160) > 0.1 * peak_rms) {
      e += f;
      n += 160;
    }
  }
  return n ? std::sqrt(e / n) : peak_rms;
}

void Scale(std::vector<float>* x, double gain) {
  for (float& v : *x) v = static_cast<float>(v * gain);
}

std::vector<float> PinkishNoise(size_t n, std::mt19937* rng) {
  std::normal_distribution<float> d(0.0f, 1.0f);
  std::vector<float> x(n);
  float b0 = 0, b1 = 0;
  for (size_t i = 0; i < n; ++i) {
    const float w = d(*rng);
    b0 = 0.97f * b0 +
         0.03f * w;  // low-frequency weighted mix: closer to room/engine noise than white
    b1 = 0.6f * b1 + 0.4f * w;
    x[i] = 4.0f * b0 + 0.5f * b1 + 0.2f * w;
  }
  return x;
}

std::vector<std::vector<float>> RealSpeech(const std::string& data_dir,
                                           std::vector<std::string>* names = nullptr) {
  std::vector<std::vector<float>> out;
  for (const std::string sub :
       {"audio/cmu_arctic", "audio/pocketsphinx_test/librivox", "audio/pocketsphinx_test/cards",
        "audio/sphinx4_digits", "audio/pocketsphinx_test"}) {
    const fs::path dir = fs::path(data_dir) / sub;
    if (!fs::exists(dir)) continue;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".wav" || e.path().extension() == ".raw")
        files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      try {
        auto b = audio::ReadAudioFile(f.string(), audio::RawFormat{16000, 1, "s16le"});
        if (b.sample_rate_hz != 16000 || b.channels.empty()) continue;
        out.push_back(b.channels[0]);
        if (names) names->push_back(f.filename().string());
      } catch (const std::exception&) {
      }
    }
  }
  return out;
}

const std::vector<std::string> kVoices = {"en-us",      "en",       "en-gb-scotland", "en-029",
                                          "en-gb-x-rp", "en-us+f3", "en+m3",          "en-us+f2"};
const std::vector<std::string> kCalls = {"help",          "help me",    "please help",
                                         "somebody help", "help help",  "can anyone help me",
                                         "help us",       "I need help"};
const std::vector<std::string> kNegativeSentences = {
    "the quick brown fox jumps over the lazy dog",
    "we walked along the river in the evening",
    "please hand me the blue folder on the desk",
    "the meeting starts at half past nine tomorrow",
    "turn left at the second corner and keep going",
    "this room is very cold in the winter",
    "she sells sea shells by the sea shore",
    "I think the robot is moving too slowly",
    "open the door and look inside the kitchen",
    "the weather was lovely on the weekend",
    "hello, can you hear me over there",
    "we should check the second floor next",
    "my phone battery is almost empty",
    "the children played football in the yard",
    "bring some water and a blanket",
    "the elevator is out of order today"};

}  // namespace

KwsEvalData MakeKwsEvalData(const KwsEvalOptions& o) {
  KwsEvalData data;
  std::mt19937 rng(o.seed);
  std::vector<std::string> real_names;
  const auto real = RealSpeech(o.data_dir, &real_names);
  std::uniform_int_distribution<int> speed(130, 180), pitch(35, 65);
  // Positives: 3.5 s scenes, call starting at 1.0 s.
  for (int i = 0; i < o.num_calls; ++i) {
    // (espeak: this exact expression fixes the evaluation's data set)
    const size_t voice = (i / kCalls.size() + i) % kVoices.size();
    std::vector<float> call =
        o.tts == "flite"
            ? Render(o.tts, kCalls[i % kCalls.size()], "", voice, speed(rng), 50)
            : RenderEspeak(kCalls[i % kCalls.size()], kVoices[voice], speed(rng), pitch(rng));
    if (call.empty()) break;
    const size_t n = 56000, start = 16000;
    std::vector<float> scene(std::max(n, start + call.size() + 8000), 0.0f);
    std::vector<float> noise = PinkishNoise(scene.size(), &rng);
    const double call_rms = ActiveRms(call);
    Scale(&call, 0.1 / call_rms);  // call at -20 dBFS RMS
    std::vector<float> babble(scene.size(), 0.0f);
    if (!real.empty()) {
      const auto& other = real[rng() % real.size()];
      for (size_t k = 0; k < babble.size() && k < other.size(); ++k) babble[k] = other[k];
      Scale(&babble, 0.1 * std::pow(10.0, o.babble_db / 20) / std::max(1e-9, ActiveRms(babble)));
    }
    // Noise so that call / (noise + babble) = call_snr_db.
    const double target_bg = 0.1 * std::pow(10.0, -o.call_snr_db / 20);
    const double babble_rms = Rms(babble);
    const double noise_rms =
        std::sqrt(std::max(target_bg * target_bg - babble_rms * babble_rms, 1e-8));
    Scale(&noise, noise_rms / std::max(1e-9, Rms(noise)));
    for (size_t k = 0; k < scene.size(); ++k) scene[k] = noise[k] + babble[k];
    for (size_t k = 0; k < call.size(); ++k) scene[start + k] += call[k];
    std::vector<float> placed(scene.size(), 0.0f);
    std::copy(call.begin(), call.end(), placed.begin() + start);
    data.positive_call.push_back(std::move(placed));
    data.positive_babble.push_back(babble);
    data.positive_noise.push_back(noise);
    data.positives.push_back(std::move(scene));
    data.call_start_s.push_back(1.0);
    data.call_end_s.push_back(1.0 + call.size() / 16000.0);
  }
  // Short synthetic confusers (own random stream: the main set is unchanged by them).
  {
    const std::vector<std::string> phrases = {"hello",     "hold on", "well done",  "yes",
                                              "thank you", "go away", "over there", "hello there",
                                              "I am fine", "come in", "held",       "yelp",
                                              "self",      "hell",    "health",     "stop"};
    std::mt19937 crng(o.seed + 1000);
    std::uniform_int_distribution<int> cspeed(130, 180), cpitch(35, 65);
    for (int i = 0; i < o.num_confusers; ++i) {
      const size_t voice = (i / phrases.size() + i) % kVoices.size();
      std::vector<float> c =
          o.tts == "flite" ? Render(o.tts, phrases[i % phrases.size()], "", voice, cspeed(crng), 50)
                           : RenderEspeak(phrases[i % phrases.size()], kVoices[voice], cspeed(crng),
                                          cpitch(crng));
      if (c.empty()) break;
      const size_t start = 16000;
      std::vector<float> scene(std::max<size_t>(56000, start + c.size() + 8000), 0.0f);
      std::vector<float> noise = PinkishNoise(scene.size(), &crng);
      Scale(&c, 0.1 / ActiveRms(c));
      Scale(&noise, 0.1 * std::pow(10.0, -o.call_snr_db / 20) / std::max(1e-9, Rms(noise)));
      for (size_t k = 0; k < scene.size(); ++k) scene[k] = noise[k];
      for (size_t k = 0; k < c.size(); ++k) scene[start + k] += c[k];
      data.confusers.push_back(std::move(scene));
    }
  }
  // Negatives: other speech in noise until negative_minutes.
  const size_t total = static_cast<size_t>(o.negative_minutes * 60 * 16000);
  std::vector<std::vector<float>> pool = real;
  std::vector<std::string> pool_names = real_names;
  std::vector<bool> pool_synthetic(real.size(), false);
  for (size_t i = 0; i < kNegativeSentences.size(); ++i) {
    auto s = Render(o.tts, kNegativeSentences[i], kVoices[i % kVoices.size()], i,
                    150 + 10 * (i % 5), 40 + 5 * (i % 6));
    if (!s.empty()) {
      pool.push_back(std::move(s));
      pool_names.push_back(std::to_string(i));
      pool_synthetic.push_back(true);
    }
  }
  if (pool.empty()) return data;
  std::uniform_real_distribution<double> gap_s(0.3, 1.5), level_db(-30, -14), rate(0.9, 1.1),
      snr(5, 20);
  data.negatives.reserve(total + 16000 * 10);
  size_t idx = 0;
  while (data.negatives.size() < total) {
    const size_t which = idx++ % pool.size();
    const auto& src = pool[which];
    std::vector<float> s =
        Resample(src, 16000, static_cast<int>(16000 * rate(rng)));  // speaking-rate change
    Scale(&s, std::pow(10.0, level_db(rng) / 20) / std::max(1e-9, ActiveRms(s)));
    const size_t gap = static_cast<size_t>(gap_s(rng) * 16000);
    std::vector<float> seg(gap + s.size(), 0.0f);
    std::copy(s.begin(), s.end(), seg.begin() + gap);
    const int64_t at = static_cast<int64_t>(data.negatives.size() + gap);
    data.negative_sources.push_back(
        {at, at + static_cast<int64_t>(s.size()),
         (pool_synthetic[which] ? "espeak:" : "real:") + pool_names[which], pool_synthetic[which]});
    std::vector<float> noise = PinkishNoise(seg.size(), &rng);
    Scale(&noise, ActiveRms(s) * std::pow(10.0, -snr(rng) / 20) / std::max(1e-9, Rms(noise)));
    for (size_t k = 0; k < seg.size(); ++k) data.negatives.push_back(seg[k] + noise[k]);
  }
  return data;
}

std::string KwsEvalData::NegativeSourceAt(double t_s, bool* synthetic) const {
  const int64_t k = static_cast<int64_t>(t_s * 16000);
  for (const auto& src : negative_sources)
    if (k >= src.start_sample - 1600 && k < src.end_sample + 1600) {  // 0.1 s tolerance (pre-roll)
      if (synthetic) *synthetic = src.synthetic;
      return src.name;
    }
  if (synthetic) *synthetic = false;
  return "gap";
}

std::vector<KwsEvalResult> EvaluateKwsSweep(const KwsEvalData& data,
                                            const KeywordOptions& keywords_in,
                                            const VadOptions& vad_options, const KwsEvalOptions& o,
                                            const std::vector<double>& cuts,
                                            const std::vector<double>& max_utterances_s,
                                            const std::vector<double>& call_joins_s,
                                            const std::vector<double>& verifier_min_probabilities) {
  KeywordOptions keywords = keywords_in;
  keywords.min_confidence = 0;
  keywords.max_utterance_s = 0;  // applied below as a post-filter (same rule as in the spotter)
  VerifierOptions verifier_options = keywords.verifier;  // applied below as a post-filter too
  keywords.verifier.enabled = false;
  KeywordSpotter spotter(keywords);
  const bool want_features =
      verifier_options.enabled || !o.fit_verifier_features.empty() || !o.features_csv.empty();
  bool with_phones = !o.features_csv.empty() || NeedsPhoneLoop(verifier_options);
  for (const auto& n : o.fit_verifier_features) with_phones |= n == "phone_distance";
  // dump "llr" also computes the (slow) acoustic verification of every hit.
  const bool dump = !o.dump.empty();
  if (o.dump == "llr") spotter.set_compute_verification(true);
  const auto t0 = std::chrono::steady_clock::now();
  struct Hit {
    double utterance_start_s;
    double t;
    std::string keyword;
    double confidence;
    double utterance_s;
    std::vector<double>
        call_s;  // per call_joins_s value: length of the call (CallGroups) holding the hit
    HitFeatures features;
    bool synthetic = false;  // negatives: the hit fell in an espeak-ng sentence
  };
  int scene = 0;  // positive scene being decoded (for segment_dir names)
  FILE* features_csv = nullptr;
  if (!o.features_csv.empty()) {
    features_csv = std::fopen(o.features_csv.c_str(), "w");
    if (!features_csv) throw std::runtime_error("cannot write " + o.features_csv);
    if (features_csv)
      std::fprintf(features_csv,
                   "set,half,scene,source,synthetic,in_call,keyword,t,call_s,log_ratio,duration_s,"
                   "ratio_per_s,"
                   "utterance_s,lead_s,trail_s,snr_db,hit_level_db,voiced_fraction,pitch_hz,pitch_"
                   "range_st,tilt_db,"
                   "phone_distance,phones\n");
  }
  const double half_stream_s = data.negatives.size() / 16000.0 / 2;
  auto run = [&](const std::vector<float>& x, std::vector<Hit>* hits) {
    VoiceActivityDetector vad(16000, vad_options);
    std::vector<Utterance> utts;
    for (size_t i = 0; i < x.size(); i += 4096)
      vad.Push(x.data() + i, std::min<size_t>(4096, x.size() - i), &utts);
    vad.Flush(&utts);
    // Per join value: the length of the call (utterances joined across short pauses) of each
    // utterance.
    std::vector<std::vector<double>> call_s(call_joins_s.size(), std::vector<double>(utts.size()));
    for (size_t j = 0; j < call_joins_s.size(); ++j) {
      const int64_t join = static_cast<int64_t>(call_joins_s[j] * 16000);
      for (size_t a = 0; a < utts.size();) {
        size_t b = a + 1;
        while (b < utts.size() && utts[b].start_sample - utts[b - 1].end_sample < join) ++b;
        for (size_t k = a; k < b; ++k)
          call_s[j][k] = (utts[b - 1].end_sample - utts[a].samples_start) / 16000.0;
        a = b;
      }
    }
    for (size_t k = 0; k < utts.size(); ++k) {
      const Utterance& u = utts[k];
      if (dump)
        std::fprintf(stderr, "UTT %s %.3f %.3f\n", &x == &data.negatives ? "neg" : "pos",
                     u.start_sample / 16000.0, u.end_sample / 16000.0);
      const auto d = spotter.Decode(u.samples.data(), u.samples.size(), false);
      if (!o.segment_dir.empty()) {
        const char* segdir = o.segment_dir.c_str();
        // Each utterance with a hit, as raw s16le, named by its label and time (for offline
        // probes).
        if (!d.keywords.empty() && u.samples.size() <= 2.0 * 16000) {
          char name[256];
          std::snprintf(name, sizeof(name), "%s/%s_%03d_%07.2f_%.2f_%s.raw", segdir,
                        &x == &data.negatives ? "neg" : "pos", scene, u.samples_start / 16000.0,
                        u.samples.size() / 16000.0, d.keywords[0].keyword.c_str());
          if (FILE* f = std::fopen(name, "wb")) {
            std::fwrite(u.samples.data(), 2, u.samples.size(), f);
            std::fclose(f);
          }
        }
      }
      for (const auto& h : d.keywords) {
        hits->push_back({u.samples_start / 16000.0,
                         u.samples_start / 16000.0 + h.start_s,
                         h.keyword,
                         h.confidence,
                         u.samples.size() / 16000.0,
                         {},
                         {},
                         false});
        for (const auto& c : call_s) hits->back().call_s.push_back(c[k]);
        const bool negative = &x == &data.negatives;
        if (negative) data.NegativeSourceAt(hits->back().t, &hits->back().synthetic);
        if (want_features)
          hits->back().features = spotter.Features(
              u.samples.data(), u.samples.size(), h, (u.start_sample - u.samples_start) / 16000.0,
              (u.end_sample - u.samples_start) / 16000.0, with_phones);
        if (features_csv) {
          const HitFeatures& f = hits->back().features;
          const double t = u.samples_start / 16000.0 + h.start_s;
          bool synthetic = true;
          std::string source = "call";
          bool in_call = false;
          const bool confuser = !negative && scene >= 1000;
          if (negative) {
            source = data.NegativeSourceAt(t, &synthetic);
          } else if (confuser) {
            source = "confuser";
          } else {
            in_call = t > data.call_start_s[scene] - 0.5 && t < data.call_end_s[scene] + 0.5;
          }
          const bool held =
              negative ? u.samples_start / 16000.0 >= half_stream_s : (scene / 8) % 2 == 1;
          std::fprintf(features_csv,
                       "%s,%s,%d,%s,%d,%d,%s,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.2f,%.2f,%."
                       "3f,%.1f,%.2f,%.2f,%.3f,%s\n",
                       negative   ? "neg"
                       : confuser ? "conf"
                                  : "pos",
                       held ? "held" : "tune", negative ? -1 : scene, source.c_str(),
                       synthetic ? 1 : 0, in_call ? 1 : 0, h.keyword.c_str(), t,
                       call_s.empty() ? 0.0 : call_s.back()[k], f.log_ratio, f.duration_s,
                       f.ratio_per_s, f.utterance_s, f.lead_s, f.trail_s, f.snr_db, f.hit_level_db,
                       f.voiced_fraction, f.pitch_hz, f.pitch_range_st, f.tilt_db, f.phone_distance,
                       f.phones.c_str());
        }
        if (dump)
          std::fprintf(stderr,
                       "HIT %s %s t %.2f ratio %.3f kconf %.3f conf %.3f dur %.2f utt %.2f call "
                       "%.2f llr %.4f\n",
                       &x == &data.negatives ? "neg" : "pos", h.keyword.c_str(),
                       u.samples_start / 16000.0 + h.start_s, h.log_ratio, h.kws_confidence,
                       h.confidence, h.end_s - h.start_s, u.samples.size() / 16000.0,
                       call_s.back()[k], h.verify_llr);
      }
    }
  };
  std::vector<std::vector<Hit>> pos(data.positives.size());
  for (size_t i = 0; i < data.positives.size(); ++i) {
    scene = static_cast<int>(i);
    run(data.positives[i], &pos[i]);
    if (dump) {
      std::fprintf(stderr, "POS %zu call %.2f-%.2f:", i, data.call_start_s[i], data.call_end_s[i]);
      for (const auto& h : pos[i])
        std::fprintf(stderr, " %s@%.2f(%.2f)", h.keyword.c_str(), h.t, h.confidence);
      std::fprintf(stderr, "\n");
    }
  }
  std::vector<std::vector<Hit>> conf(data.confusers.size());
  for (size_t i = 0; i < data.confusers.size(); ++i) {
    scene = 1000 + static_cast<int>(i);
    run(data.confusers[i], &conf[i]);
  }
  std::vector<Hit> neg;
  run(data.negatives, &neg);
  if (features_csv) std::fclose(features_csv);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Any keyphrase holding the target word ("help me" for "help") counts as the target.
  auto is_target = [&](const Hit& h) {
    std::istringstream ws(h.keyword);
    std::string w;
    while (ws >> w)
      if (w == o.target) return true;
    return false;
  };
  auto in_call = [&](size_t i, const Hit& h) {
    return h.t > data.call_start_s[i] - 0.5 && h.t < data.call_end_s[i] + 0.5;
  };
  const double half_s = data.negatives.size() / 16000.0 / 2;
  if (!o.fit_verifier_features.empty()) {
    std::vector<HitFeatures> x;
    std::vector<int> y;
    for (size_t i = 0; i < pos.size(); ++i) {
      if ((i / kCalls.size()) % 2 == 1) continue;  // held-out scene
      for (const auto& h : pos[i])
        if (is_target(h) && in_call(i, h) &&
            (h.call_s.empty() || h.call_s.back() <= o.fit_max_call_s)) {
          x.push_back(h.features);
          y.push_back(1);
        }
    }
    for (const auto& h : neg)
      if (is_target(h) && h.utterance_start_s < half_s) {
        x.push_back(h.features);
        y.push_back(0);
      }
    verifier_options = FitKeywordVerifier(x, y, o.fit_verifier_features, o.fit_l2);
  }
  KeywordVerifier verifier(verifier_options);
  std::vector<double> vcuts = verifier_min_probabilities;
  if (vcuts.empty()) vcuts = {verifier_options.enabled ? verifier_options.min_probability : -1.0};
  std::vector<KwsEvalResult> out;
  for (size_t j = 0; j < call_joins_s.size(); ++j)
    for (double max_utt : max_utterances_s)
      for (double cut_value : cuts)
        for (double vcut : vcuts) {
          // A hit counts when its confidence reaches the cut, its utterance is short enough and the
          // verifier (if any) accepts it.
          auto verified = [&](const Hit& h) {
            return vcut < 0 || verifier.Probability(h.features) >= vcut;
          };
          auto passes = [&](const Hit& h) {
            return h.confidence >= cut_value && (max_utt <= 0 || h.call_s[j] <= max_utt) &&
                   verified(h);
          };
          KwsEvalResult r;
          r.verifier_min_probability = vcut;
          r.verifier = verifier_options;
          if (vcut >= 0) {
            int calls_hits = 0, calls_pass = 0, real_hits = 0, real_pass = 0, syn_hits = 0,
                syn_pass = 0;
            for (size_t i = 0; i < pos.size(); ++i)
              for (const auto& h : pos[i])
                if (is_target(h) && in_call(i, h)) {
                  ++calls_hits;
                  calls_pass += verified(h);
                }
            for (const auto& h : neg)
              if (is_target(h)) {
                (h.synthetic ? syn_hits : real_hits)++;
                (h.synthetic ? syn_pass : real_pass) += verified(h);
              }
            r.verifier_pass_calls = calls_hits ? static_cast<double>(calls_pass) / calls_hits : 0;
            r.verifier_pass_real = real_hits ? static_cast<double>(real_pass) / real_hits : 0;
            r.verifier_pass_synthetic = syn_hits ? static_cast<double>(syn_pass) / syn_hits : 0;
          }
          r.max_utterance_s = max_utt;
          r.call_join_s = call_joins_s[j];
          r.threshold = keywords.thresholds.empty() ? 0 : keywords.thresholds[0];
          r.min_confidence = cut_value;
          for (size_t i = 0; i < pos.size(); ++i) {
            bool found = false;
            for (const auto& h : pos[i])
              found |= passes(h) && is_target(h) && h.t > data.call_start_s[i] - 0.5 &&
                       h.t < data.call_end_s[i] + 0.5;
            r.hits += found;
            ++r.calls;
          }
          r.recall = r.calls ? static_cast<double>(r.hits) / r.calls : 0;
          for (const auto& c : conf) {
            bool any = false;
            for (const auto& h : c) any |= passes(h) && is_target(h);
            r.confuser_false_alarms += any;
            ++r.confuser_scenes;
          }
          for (size_t i = 0; i < pos.size(); ++i) {
            bool found = false;
            for (const auto& h : pos[i])
              found |= passes(h) && is_target(h) && h.t > data.call_start_s[i] - 0.5 &&
                       h.t < data.call_end_s[i] + 0.5;
            // Calls cycle through the 8 phrasings: alternate blocks of 8 so both halves hold every
            // phrasing (phrasings differ in length, and length matters to the call-shape rule).
            const bool held = (i / kCalls.size()) % 2 == 1;
            (held ? r.held_calls : r.tune_calls)++;
            (held ? r.held_hits : r.tune_hits) += found;
          }
          for (const auto& h : neg)
            if (passes(h)) {
              const bool target = is_target(h);
              (target ? r.target_false_alarms : r.other_false_alarms)++;
              if (target)
                (h.utterance_start_s < half_s ? r.tune_false_alarms : r.held_false_alarms)++;
              if (target && h.utterance_start_s < half_s)
                (h.synthetic ? r.tune_fa_synthetic : r.tune_fa_real)++;
              if (target && h.utterance_start_s >= half_s)
                (h.synthetic ? r.held_fa_synthetic : r.held_fa_real)++;
            }
          r.negative_minutes = data.negatives.size() / 16000.0 / 60.0;
          const double half_min = r.negative_minutes / 2;
          r.tune_recall = r.tune_calls ? static_cast<double>(r.tune_hits) / r.tune_calls : 0;
          r.held_recall = r.held_calls ? static_cast<double>(r.held_hits) / r.held_calls : 0;
          r.tune_fa_per_10_min = half_min > 0 ? r.tune_false_alarms * 10.0 / half_min : 0;
          r.held_fa_per_10_min = half_min > 0 ? r.held_false_alarms * 10.0 / half_min : 0;
          r.false_alarms_per_10_min =
              r.negative_minutes > 0 ? r.target_false_alarms * 10.0 / r.negative_minutes : 0;
          r.decode_seconds = seconds;
          out.push_back(r);
        }
  return out;
}

KwsArrayResult KwsArrayRecall(const KwsEvalData& data, const std::string& array_yaml,
                              const KeywordOptions& keywords, double call_az_deg,
                              double babble_az_deg, const VadOptions& vad, bool post_filter) {
  const auto geometry = sound::ArrayGeometry::FromOptions(common::LoadMicArray(array_yaml));
  SpeechOptions so;
  so.keywords = keywords;
  so.keywords.min_confidence = 0;
  so.vad = vad;
  so.enhancer.post_filter = post_filter;
  sound::Room room;
  const Eigen::Vector3d centre(3, 2.5, 1.0);
  auto at = [&](double az_deg, double el_deg, double r) {
    const double az = az_deg * M_PI / 180, el = el_deg * M_PI / 180;
    return Eigen::Vector3d(centre + r * Eigen::Vector3d(std::cos(el) * std::cos(az),
                                                        std::cos(el) * std::sin(az), std::sin(el)));
  };
  const sound::Direction call_dir{call_az_deg * M_PI / 180, 10 * M_PI / 180};
  const sound::Direction babble_dir{babble_az_deg * M_PI / 180, 10 * M_PI / 180};
  // The first second is the fresh processor's cold start (no noise statistics yet: its beam
  // passes the noise unsuppressed for ~0.3 s), which a node running all along never has.
  constexpr int64_t kColdStartSamples = 16000;
  KwsArrayResult result;
  for (size_t i = 0; i < data.positive_call.size(); ++i) {
    // A fresh processor per scene (as the mono evaluation starts a fresh VAD per scene): its VAD
    // learns the floor from the scene's own background.
    SpeechProcessor processor(geometry, sound::DoaKind::kAzimuthElevation, so);
    const size_t n = data.positive_call[i].size();
    const auto mics = sound::SimulateRoom(room, geometry.positions_m.colwise() + centre,
                                          {{at(call_az_deg, 10, 1.5), data.positive_call[i]},
                                           {at(babble_az_deg, 10, 1.5), data.positive_babble[i]},
                                           {at(180, 40, 2.0), data.positive_noise[i]}},
                                          n, 1e-4, static_cast<uint32_t>(i + 1));
    // Warm-up: the scene's background alone first (the node runs continuously, so its noise
    // estimates, beam and VAD floor have heard the room before a call). Calls are counted in the
    // second part.
    auto warm = sound::SimulateRoom(room, geometry.positions_m.colwise() + centre,
                                    {{at(babble_az_deg, 10, 1.5), data.positive_babble[i]},
                                     {at(180, 40, 2.0), data.positive_noise[i]}},
                                    n, 1e-4, static_cast<uint32_t>(i + 1000));
    for (size_t m = 0; m < warm.size(); ++m)
      warm[m].insert(warm[m].end(), mics[m].begin(), mics[m].end());
    const auto pcm = audio::ToInterleavedInt16(warm, 0, 2 * n);
    const int64_t offset = static_cast<int64_t>(n);
    std::vector<SpeechResult> results;
    const int ch = geometry.num_mics();
    for (size_t k = 0; k < 2 * n; k += 512) {
      processor.UpdateTrack(1, call_dir, Eigen::Matrix2d::Identity() * 0.003,
                            static_cast<int64_t>(k));
      if (data.positive_babble[i].size() == n && Rms(data.positive_babble[i]) > 1e-6)
        processor.UpdateTrack(2, babble_dir, Eigen::Matrix2d::Identity() * 0.003,
                              static_cast<int64_t>(k));
      processor.Push(pcm.data() + k * ch, static_cast<int>(std::min<size_t>(512, 2 * n - k)), ch,
                     &results);
    }
    processor.Flush(&results);  // ends the scene's last call
    bool found = false;
    for (const auto& r : results) {
      if (r.keyword.find("help") == std::string::npos) continue;
      const double t = (r.start_sample - offset) / 16000.0;
      const bool in_call = t > data.call_start_s[i] - 0.5 && t < data.call_end_s[i] + 0.5;
      found |= r.track_id == 1 && in_call;
      if (!in_call && r.start_sample >= kColdStartSamples) ++result.false_hits;
    }
    result.hits += found;
    ++result.calls;
    result.false_hit_seconds += (2.0 * n - kColdStartSamples) / 16000.0;
  }
  return result;
}

KwsEvalResult EvaluateKws(const KwsEvalData& data, const KeywordOptions& keywords,
                          const VadOptions& vad, const KwsEvalOptions& o) {
  return EvaluateKwsSweep(data, keywords, vad, o, {keywords.min_confidence},
                          {keywords.max_utterance_s}, {keywords.call_join_s})
      .front();
}

}  // namespace speech
}  // namespace sarmap
