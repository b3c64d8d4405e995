// prt meshprep: validate, weld, give normals to and optionally decimate a mesh, writing a bundle (lib/mesh).
#include "cli.h"

#include "mesh.h"

#include <memory>

#ifndef PRT_VERSION
#define PRT_VERSION "0.0.0"
#endif

namespace prt::cli {

void addMeshprepCommand(CLI::App& app) {
    auto options = std::make_shared<MeshprepOptions>();
    CLI::App* command =
        app.add_subcommand("meshprep", "Validate and clean a mesh (.obj .ply .off .stl .gltf .glb) into a bundle (.glb)");
    command->add_option("input", options->input, "Input mesh")->required();
    command->add_option("-o,--output", options->output, "Output bundle (.glb)")->required();
    outputFile(command->add_option("--report", options->report, "Write a JSON report: counts, bounds, boundary, fixes, vertex map"));
    command
        ->add_option("--weld-tolerance", options->weldTolerance, "Weld vertices closer than this times the bounding box diagonal")
        ->capture_default_str();
    command->add_flag("--weld-ignore-attributes", options->weldIgnoreAttributes,
                      "Weld across texture seams and hard edges (by default vertices with different attributes stay apart)");
    command->add_flag("--recompute-normals", options->recomputeNormals, "Compute normals even when the file has them");
    command->add_option("--decimate-to", options->decimateTo, "Decimate to this many triangles")->check(CLI::PositiveNumber);
    command->add_option("--scale", options->scale, "Scale positions uniformly by this factor")->capture_default_str();
    command->add_flag("--flatten", options->flatten,
                      "Merge a glTF scene into one welded mesh (by default a glTF input is kept as the asset: its node "
                      "tree, instances, materials and textures, with normals added where missing)");
    command->callback([options] {
        options->toolVersion = PRT_VERSION;
        runMeshprep(*options);
    });
}

} // namespace prt::cli
