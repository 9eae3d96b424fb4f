// async_array_wavgen OUT_DIR [SECONDS]: recordings of an asynchronous array for the multi-process
// test (async_cards_netns_test.sh). A ReSpeaker-shaped square (4.57 cm) whose four microphones
// sit on three sound cards, each with its own clock:
//   card0: 2 channels = microphones 0, 1 (the reference clock: tau 0, drift 0)
//   card1: 2 channels = room noise on channel 0, microphone 2 on channel 1; tau +1.3 ms, +80 ppm
//   card2: 1 channel  = microphone 3;                                   tau -0.7 ms, -120 ppm
// A white-noise source at azimuth 47.3 deg, elevation 20 deg, 1.5 m away in an anechoic room
// starts after 1 s of sensor noise (the localiser's activity gate learns its floor). Writes
// card0.wav card1.wav card2.wav and array.yaml (geometry, channel_map, start offsets and drifts
// as sarmap-mic-calibrate would give them). Each card's file starts at its own sample 0, as a
// separate capture process would count.
//
// Clock model (async_alignment.h): card sample k records the synchronous signal at reference
// sample r = (k - tau fs) / (1 + delta).
#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "audio_capture/audio_file.h"
#include "sound_localisation/testing/room_simulation.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  if (argc < 2) {
    std::fprintf(stderr, "usage: async_array_wavgen OUT_DIR [SECONDS]\n");
    return 2;
  }
  const std::string dir = argv[1];
  const double seconds = argc > 2 ? std::stod(argv[2]) : 6.0;
  std::filesystem::create_directories(dir);
  const int fs = 16000;
  const double h = 0.02285;
  Eigen::Matrix3Xd mics(3, 4);
  mics << h, -h, -h, h,  //
      h, h, -h, -h,      //
      0.005, 0.005, 0.005, 0.005;
  const double az = 47.3 * M_PI / 180, el = 20.0 * M_PI / 180;
  const Eigen::Vector3d centre(3, 2.5, 1.0);
  const Eigen::Vector3d u(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const size_t n = static_cast<size_t>(seconds * fs), lead = fs;
  std::mt19937 rng(7);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  std::vector<float> source(n, 0.0f);
  for (size_t i = lead; i < n; ++i) source[i] = 0.05f * normal(rng);
  sound::Room room;
  const auto sync =
      sound::SimulateRoom(room, mics.colwise() + centre, {{centre + 1.5 * u, source}}, n, 2e-4, 3);

  // Per microphone: card, channel on that card; per card: channels, tau, drift.
  const int mic_card[4] = {0, 0, 1, 2}, mic_channel[4] = {0, 1, 1, 0};
  const int card_channels[3] = {2, 2, 1};
  const double card_tau_s[3] = {0.0, 0.0013, -0.0007}, card_drift[3] = {0.0, 80e-6, -120e-6};
  for (int c = 0; c < 3; ++c) {
    audio::AudioBuffer buf;
    buf.sample_rate_hz = fs;
    buf.channels.assign(card_channels[c], std::vector<float>(n, 0.0f));
    for (auto& ch : buf.channels)
      for (float& v : ch) v = 2e-4f * normal(rng);  // channels without a microphone: noise
    for (int m = 0; m < 4; ++m)
      if (mic_card[m] == c)
        buf.channels[mic_channel[m]] =
            sarmap::sound::RecordAsynchronously(sync[m], card_tau_s[c], card_drift[c], fs, 48);
    audio::WriteWav(dir + "/card" + std::to_string(c) + ".wav", buf);
  }
  std::ofstream y(dir + "/array.yaml");
  y << "# written by async_array_wavgen: ReSpeaker-shaped array on three cards\n"
    << "name: async_respeaker\nsample_rate_hz: 16000\nspeed_of_sound_mps: 343.0\ngeometry: planar\n"
    << "channel_map: [0, 1, 1, 0]\n"
    << "mic_positions_m: [" << h << ", " << h << ", 0.005,  " << -h << ", " << h << ", 0.005,  "
    << -h << ", " << -h << ", 0.005,  " << h << ", " << -h << ", 0.005]\n";
  y << "start_offsets_s: [0.0, 0.0, " << card_tau_s[1] << ", " << card_tau_s[2] << "]\n"
    << "clock_drift: [0.0, 0.0, " << card_drift[1] << ", " << card_drift[2] << "]\n"
    << "sensor_model: constant\ndoa_sigma_deg: 3.0\n";
  std::printf(
      "wrote %s/card{0,1,2}.wav and array.yaml: source azimuth 47.3 deg, elevation 20 deg, %.1f "
      "s\n",
      dir.c_str(), seconds);
  return 0;
}
