#pragma once
// What sarmap-sound-localisation does with audio, without the transport: the node's options
// (config/sound_localisation.yaml), the localiser (and the optional second one whose stream
// the sound map reads), the per-direction sound classes, and the conversion of their outputs
// to doa_t messages. The node (sound_localisation_node.cc) checks and sequences the blocks and
// publishes; the in-process mission (components/mission) feeds DoaStream directly.

#include <memory>
#include <string>
#include <vector>

#include "common/options.h"
#include "common/robot_config.h"
#include "sarmap/doa_t.hpp"
#include "sound_localisation/localiser.h"
#include "sound_localisation/source_class.h"

namespace sarmap {
namespace sound {

struct SoundLocalisationOptions {
  std::string audio_channel = "AUDIO";
  std::string doa_channel = "DOA";
  std::string array = "config/arrays/respeaker4.yaml";
  std::string device_id = "";  // accept only this device ("" = the first one heard)
  // Longest run of lost samples (dropped datagrams) bridged without restarting the analysis.
  double max_bridged_gap_s = 0.25;
  bool publish_untracked = true;  // also publish directions not (yet) in a confirmed track
  // Asynchronous array (several cards, each its own process on AUDIO_<DEVICE>): the device of
  // each microphone; channel_map then gives the channel within that device. The streams are
  // aligned by sample counter, start_offsets_s and clock_drift of the array file before DOA.
  std::vector<std::string> devices;         // device ids, e.g. [card0, card1]
  std::vector<int> mic_devices;             // per microphone: index into devices
  std::vector<std::string> audio_channels;  // extra input channels (AUDIO_<DEVICE>)
  LocaliserOptions localiser;
  // A second DOA stream for the sound map, from its own localiser over the same audio (e.g.
  // precedence-effect onset bins, which place a talker near a wall better but give sparser
  // tracks than sarmap-speech's beams want). Empty: none.
  std::string map_doa_channel = "";
  LocaliserOptions map_localiser;
  // What each direction's source is (doa_source_t sound_class), from its own time-frequency bins.
  bool classify = true;
  SourceClassOptions classes;
  template <class V>
  void Visit(V& v) {
    v("audio_channel", audio_channel, "input audio_frame_t channel");
    v("doa_channel", doa_channel, "output doa_t channel");
    v("array", array, "array description (config/arrays/<name>.yaml)");
    v("device_id", device_id,
      "only use this device ('' = the first one heard); others are dropped and reported");
    v("max_bridged_gap_s", max_bridged_gap_s,
      "a gap in the audio up to this long is bridged (analysis goes on); longer ones restart it",
      NonNegative());
    v("publish_untracked", publish_untracked,
      "publish directions outside confirmed tracks with track_id -1");
    v("devices", devices, "asynchronous array: device ids of its cards ([] = one device)");
    v("mic_devices", mic_devices, "asynchronous array: index into devices of each microphone");
    v("audio_channels", audio_channels, "further input channels (one per card, AUDIO_<DEVICE>)");
    v("localiser", localiser, "DOA estimation and tracking");
    v("map_doa_channel", map_doa_channel,
      "second doa_t stream for the sound map, from map_localiser ('' = none)");
    v("map_localiser", map_localiser, "DOA estimation and tracking of the map_doa_channel stream");
    v("classify", classify, "tell each direction's source class (voice, alarm, machinery, music)");
    v("classes", classes, "source classification");
  }
  void Validate(common::Validator& check) const {
    for (int d : mic_devices)
      check.That(d >= 0 && d < static_cast<int>(devices.size()), "mic_devices",
                 "indices must point into devices");
    check.That(devices.empty() || !mic_devices.empty(), "mic_devices", "needed with devices");
  }
};

// doa_source_t::METHOD_* of a localiser method name.
int8_t MethodCode(const std::string& method);

class DoaStream {
 public:
  // `array_dir`: where the array file's relative paths (sensor model) are. Throws
  // std::invalid_argument on an unusable array or options.
  DoaStream(const SoundLocalisationOptions& options, const common::MicArrayOptions& array,
            const std::string& array_dir);

  const ArrayGeometry& geometry() const { return geometry_; }
  bool has_map_stream() const { return map_localiser_ != nullptr; }
  int64_t samples_seen() const { return localiser_->samples_seen(); }
  void set_device(const std::string& device) { device_ = device; }

  // Lost samples bridged (the time line advances) / the analysis restarted.
  void SkipSamples(int64_t samples);
  void ResetStream();
  // One interleaved int16 block whose first sample (stream sample samples_seen()) was taken at
  // `utime`: the DOA messages of the localiser (`doa`) and of the map localiser (`map_doa`)
  // for every analysis block it completed.
  void Push(const int16_t* data, int frames, int block_channels, int64_t utime,
            std::vector<sarmap::doa_t>* doa, std::vector<sarmap::doa_t>* map_doa);
  // Aligned float channels (asynchronous arrays); stream sample `base_sample` was taken at
  // `base_utime`.
  void PushFloat(const std::vector<std::vector<float>>& mic_channels, size_t count,
                 int64_t base_utime, int64_t base_sample, std::vector<sarmap::doa_t>* doa,
                 std::vector<sarmap::doa_t>* map_doa);

 private:
  // The outputs of one localiser as messages; utime of stream sample s = base_utime + (s -
  // base_sample) / rate.
  void Messages(const std::vector<LocaliserOutput>& stream, const LocaliserOptions& lo,
                int64_t base_utime, int64_t base_sample, std::vector<sarmap::doa_t>* out);

  SoundLocalisationOptions options_;
  ArrayGeometry geometry_;
  std::unique_ptr<Localiser> localiser_, map_localiser_;
  std::unique_ptr<DirectionalClassifier> classifier_;
  std::string device_;
  std::vector<LocaliserOutput> outs_, map_outs_;
};

}  // namespace sound
}  // namespace sarmap
