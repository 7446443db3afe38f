// Reads an OctoMap that sndt wrote with liboctomap itself and lists every leaf, so that
// sndt's own map can be queried at each leaf's centre (host/examples/octomap_check.rs).
//
//   check_octomap bt  FILE RES OUT   a .bt file, octomap::OcTree::readBinary
//   check_octomap ot  FILE RES OUT   a .ot file, octomap::AbstractOcTree::read, must be a ColorOcTree
//   check_octomap msg FILE RES OUT   the data of an octomap_msgs/Octomap (binary, OcTree), read
//                                    as octomap_msgs' binaryMsgToMap does: OcTree(RES).readBinaryData
//
// Fails unless the file reads, the resolution is RES, the tree is 16 levels deep and
// liboctomap, given the leaves it read, encodes them into the very bytes of the file: a new
// tree of the same kind with each leaf set by its key (lazily, so nothing is pruned, as sndt
// does not prune), inner nodes filled by updateInnerOccupancy (for a ColorOcTree: largest
// log-odds, mean colour), written by writeBinaryData (bt, msg) or writeData (ot). OUT gets
// one line per leaf: "x y z depth occupied log_odds" (centre in metres, depth 16 is one
// voxel, occupied per isNodeOccupied), then " r g b" for a ColorOcTree. Prints a one-line
// summary.
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
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

void copy_color(octomap::OcTreeNode&, const octomap::OcTreeNode&) {}

void copy_color(octomap::ColorOcTreeNode& to, const octomap::ColorOcTreeNode& from) {
    to.setColor(from.getColor());
}

void write_tree(const octomap::OcTree& tree, std::ostream& s) { tree.writeBinaryData(s); }

void write_tree(const octomap::ColorOcTree& tree, std::ostream& s) { tree.writeData(s); }

// liboctomap's own encoding of the leaves of `tree` (see the top of the file).
template <class Tree>
std::string encode_again(const Tree& tree) {
    Tree fresh(tree.getResolution());
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
        auto* node = fresh.setNodeValue(it.getKey(), it->getLogOdds(), true);
        // setNodeValue clamps to OctoMap's default thresholds; keep the value as read.
        node->setLogOdds(it->getLogOdds());
        copy_color(*node, *it);
    }
    fresh.updateInnerOccupancy();
    std::ostringstream s;
    write_tree(fresh, s);
    return s.str();
}

// The tree bytes of a file: after the header's "data" line, or all of it (a message's data).
std::string tree_bytes(const std::string& file, bool header) {
    std::ifstream in(file, std::ios_base::binary);
    std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!header) {
        return all;
    }
    const size_t at = all.find("\ndata\n");
    return at == std::string::npos ? std::string() : all.substr(at + 6);
}

// Writes the leaves of `tree` to `path` and prints the summary; 0 when all is well.
template <class Tree>
int dump(const Tree& tree, double res, const std::string& what, const std::string& path,
         const std::string& bytes) {
    const std::string again = encode_again(tree);
    if (again != bytes) {
        return fail(what + ": liboctomap encodes these leaves into " + std::to_string(again.size()) +
                    " other bytes than the file's " + std::to_string(bytes.size()));
    }
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
                "leaf depths %u..%u; liboctomap's encoding of them = the file's %zu bytes\n",
                what.c_str(), tree.getTreeType().c_str(), tree.getResolution(), tree.size(), leaves,
                occupied, leaves - occupied, leaves ? min_depth : 0, max_depth, bytes.size());
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
        return dump(tree, res, what, out, tree_bytes(file, true));
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
        return dump(*color_tree, res, what, out, tree_bytes(file, true));
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
        return dump(tree, res, what, out, tree_bytes(file, false));
    }
    return fail("unknown mode " + mode);
}
