// Localises one touch with an installed VTLoc, through <vtloc/vtloc.h> only.
//   vtloc_example_consumer MODEL OBJECT TACTILE [HEATMAP.ply]
#include <cstdio>
#include <vtloc/vtloc.h>

int main(int argc, char** argv) {
    if (argc < 4 || argc > 5) {
        std::fprintf(stderr, "usage: %s MODEL.safetensors OBJECT.glb|.ply TACTILE.png [HEATMAP.ply]\n", argv[0]);
        return 2;
    }
    try {
        vtloc::api::Context ctx;  // best device; VTLOC_DEVICE / VTLOC_VALIDATION apply
        vtloc::api::Model model(ctx, argv[1]);
        vtloc::api::Object object = model.encode_object(argv[2]);
        vtloc::api::TouchResult r = model.localize(object, vtloc::api::load_tactile_image(argv[3]));

        std::printf("vtloc %s on %s: model %s, %zu object points\n", vtloc::api::version(), ctx.device().name.c_str(),
                    model.info().name.c_str(), object.cloud().size());
        std::printf("contact (%.2f, %.2f, %.2f) in the object's units\n", r.contact[0], r.contact[1], r.contact[2]);
        for (size_t k = 0; k < r.topk_index.size(); ++k)
            std::printf("  top-%zu: point %d (%.2f, %.2f, %.2f)\n", k + 1, r.topk_index[k], r.topk_point[k][0],
                        r.topk_point[k][1], r.topk_point[k][2]);
        if (r.alignment) std::printf("alignment score %.4f\n", *r.alignment);
        if (argc == 5) vtloc::api::write_heatmap_ply(argv[4], object, r.heatmap);

        auto messages = ctx.take_validation_messages();
        for (const std::string& m : messages) std::fprintf(stderr, "validation layer: %s\n", m.c_str());
        return messages.empty() ? 0 : 1;
    } catch (const vtloc::api::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
