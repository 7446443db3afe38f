// Reads an OctoMap that sndt wrote with liboctomap itself and lists every leaf, so that
// sndt's own map can be queried at each leaf's centre (host/examples/octomap_check.rs).
//
//   check_octomap bt  FILE RES OUT   a .bt file, octomap::OcTree::readBinary
//   check_octomap ot  FILE RES OUT   a .ot file, octomap::AbstractOcTree::read, must be a ColorOcTree
//   check_octomap msg FILE RES OUT   the data of an octomap_msgs/Octomap (binary, OcTree), read
//                                    as octomap_msgs' binaryMsgToMap does: OcTree(RES).readBinaryData
//
// Fails unless the file reads, the resolution is RES and the tree is 16 levels deep. OUT
// gets one line per leaf: "x y z depth occupied log_odds" (centre in metres, depth 16 is
// one voxel, occupied per isNodeOccupied), then " r g b" for a ColorOcTree. Prints a
// one-line summary.
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>

namespace {

int fail(const std::string& why) {
    std::fprintf(stderr, "check_octomap: %s\n", why.c_str());
    return 1;
}

void color(std::FILE*, const octomap::OcTreeNode&) {}

void color(std::FILE* out, const octomap::ColorOcTreeNode& n) {
    const octomap::ColorOcTreeNode::Color c = n.getColor();
    std::fprintf(out, " %u %u %u", unsigned(c.r), unsigned(c.g), unsigned(c.b));
}

// Writes the leaves of `tree` to `path` and prints the summary; 0 when all is well.
template <class Tree>
int dump(const Tree& tree, double res, const std::string& what, const std::string& path) {
    if (tree.getResolution() != res) {
        return fail(what + ": resolution " + std::to_string(tree.getResolution()) +
                    ", expected " + std::to_string(res));
    }
    if (tree.getTreeDepth() != 16) {
        return fail(what + ": tree depth " + std::to_string(tree.getTreeDepth()));
    }
    std::FILE* out = std::fopen(path.c_str(), "w");
    if (!out) {
        return fail("cannot write " + path);
    }
    size_t leaves = 0, occupied = 0;
    unsigned min_depth = 16, max_depth = 0;
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
        const bool occ = tree.isNodeOccupied(*it);
        std::fprintf(out, "%.9g %.9g %.9g %u %d %.9g", it.getX(), it.getY(), it.getZ(),
                     it.getDepth(), occ ? 1 : 0, it->getLogOdds());
        color(out, *it);
        std::fputc('\n', out);
        ++leaves;
        occupied += occ ? 1 : 0;
        min_depth = std::min(min_depth, it.getDepth());
        max_depth = std::max(max_depth, it.getDepth());
    }
    if (std::fclose(out) != 0) {
        return fail("cannot write " + path);
    }
    std::printf("liboctomap %s: %s, res %g, depth 16, %zu nodes, %zu leaves (%zu occupied, %zu free), "
                "leaf depths %u..%u\n",
                what.c_str(), tree.getTreeType().c_str(), tree.getResolution(), tree.size(), leaves,
                occupied, leaves - occupied, leaves ? min_depth : 0, max_depth);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 5) {
        return fail("usage: check_octomap bt|ot|msg FILE RES OUT");
    }
    const std::string mode = argv[1], file = argv[2], out = argv[4];
    const double res = std::strtod(argv[3], nullptr);
    const std::string what = mode + " " + file;
    if (mode == "bt") {
        octomap::OcTree tree(0.1);
        // readBinary checks the header and that the node count matches its `size`.
        if (!tree.readBinary(file)) {
            return fail(what + ": OcTree::readBinary failed");
        }
        return dump(tree, res, what, out);
    }
    if (mode == "ot") {
        std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(file));
        if (!tree) {
            return fail(what + ": AbstractOcTree::read failed");
        }
        auto* color_tree = dynamic_cast<octomap::ColorOcTree*>(tree.get());
        if (!color_tree) {
            return fail(what + ": a " + tree->getTreeType() + ", not a ColorOcTree");
        }
        return dump(*color_tree, res, what, out);
    }
    if (mode == "msg") {
        std::ifstream in(file, std::ios_base::binary);
        if (!in) {
            return fail("cannot read " + file);
        }
        octomap::OcTree tree(res);
        tree.readBinaryData(in);
        // A short read sets failbit; reading exactly to the end does not.
        if (in.fail()) {
            return fail(what + ": readBinaryData ran out of data");
        }
        // Everything read, nothing left over: the data is exactly one tree.
        if (in.peek() != std::ifstream::traits_type::eof()) {
            return fail(what + ": bytes after the tree");
        }
        return dump(tree, res, what, out);
    }
    return fail("unknown mode " + mode);
}
