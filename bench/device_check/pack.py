#!/usr/bin/env python3
"""Packs a built tree for a Linux x86-64 GPU machine that has a Vulkan driver but
none of our -dev packages (a robot's computer, a lent test machine): the test
runner, the CLI and the benches, the libraries they load, the Khronos validation
layer, and the test list in shards. run.sh (copied beside the pack) runs it there.

Usage: python3 bench/device_check/pack.py [--build build] [--out .devcheck]
Needs the Debian 12 build machine's packages and its apt archive (for the Vulkan
loader and the reference LAPACK, fetched as .deb files and unpacked, not
installed)."""
import argparse, os, re, shutil, subprocess, sys, tempfile

ap = argparse.ArgumentParser()
ap.add_argument('--build', default='build')
ap.add_argument('--out', default='.devcheck')
args = ap.parse_args()
B = os.path.abspath(args.build)
OUT = os.path.abspath(args.out)
LIBDIRS = ['/lib/x86_64-linux-gnu', '/usr/lib/x86_64-linux-gnu']
# Left to the machine: glibc 2.35+ and libstdc++ of GCC 12+ (Debian 12, Ubuntu
# 22.04 or newer; the packed files need GLIBC_2.35 and GLIBCXX_3.4.30), and zlib.
SYSTEM = {'libc.so.6', 'libm.so.6', 'libstdc++.so.6', 'libgcc_s.so.1', 'libpthread.so.0', 'libdl.so.2',
          'librt.so.1', 'ld-linux-x86-64.so.2', 'libz.so.1'}
DEBS = {'liblapack3': {'liblapack.so.3': 'lapack/liblapack.so.3'}, 'libblas3': {'libblas.so.3': 'blas/libblas.so.3'},
        'libgfortran5': {'libgfortran.so.5': 'libgfortran.so.5'}, 'libquadmath0': {'libquadmath.so.0': 'libquadmath.so.0'}}
GL_DEBS = ['libvulkan1', 'libglvnd0', 'libglx0', 'libegl1', 'libgl1', 'libopengl0', 'libgles2']
BINS = ['tests/vtloc_tests', 'vtloc', 'vtloc-bench', 'vtloc-bench-point', 'vtloc-bench-tactile', 'vtloc-bench-probe']
LAYER = '/usr/lib/x86_64-linux-gnu/libVkLayer_khronos_validation.so'
SHARDS = 12  # test processes at once on the GPU machine
LAYER_JSON = '/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json'


def sh(cmd, **kw):
    return subprocess.run(cmd, check=True, capture_output=True, text=True, **kw).stdout


def needed(path):
    return re.findall(r'Shared library: \[(.+?)\]', sh(['readelf', '-d', path]))


def find_lib(name):
    for d in LIBDIRS:
        if os.path.exists(os.path.join(d, name)):
            return os.path.realpath(os.path.join(d, name))
    sys.exit(f'pack: {name} not found in {LIBDIRS}')


def apt_download(pkgs, dest):
    """Fetches `pkgs` as .deb files into `dest` with lists and cache of its own."""
    os.makedirs(dest, exist_ok=True)
    with tempfile.TemporaryDirectory() as state:
        os.makedirs(state + '/lists/partial')
        os.makedirs(state + '/cache/archives/partial')
        o = ['-oAPT::Architecture=amd64', '-oAPT::Architectures=amd64', '-oDir::State::Lists=' + state + '/lists',
             '-oDir::Cache=' + state + '/cache']
        sh(['apt-get', *o, 'update'])
        sh(['apt-get', *o, 'download', *pkgs], cwd=dest)


def main():
    with tempfile.TemporaryDirectory() as work:
        pack(work)


def pack(work):
    root = os.path.join(work, 'bundle')
    for d in ('bin', 'lib', 'layer'):
        os.makedirs(os.path.join(root, d))
    real = {}
    debdir = os.path.join(work, 'debs')
    apt_download(list(DEBS), debdir)
    for f in os.listdir(debdir):
        sh(['dpkg', '-x', os.path.join(debdir, f), os.path.join(work, 'x')])
    for libs in DEBS.values():
        for name, rel in libs.items():
            real[name] = os.path.join(work, 'x/usr/lib/x86_64-linux-gnu', rel)
    # The closure of what the programs and the layer load, minus system and deb libraries.
    carried, todo = {}, [os.path.join(B, b) for b in BINS] + [LAYER]
    while todo:
        for n in needed(todo.pop()):
            if n in SYSTEM or n in real or n in carried:
                continue
            carried[n] = find_lib(n)
            todo.append(carried[n])
    for b in BINS:
        dst = os.path.join(root, 'bin', os.path.basename(b))
        shutil.copy(os.path.join(B, b), dst)
        sh(['strip', dst])
    for n, p in list(carried.items()) + list(real.items()) + [(os.path.basename(LAYER), LAYER)]:
        dst = os.path.join(root, 'lib', n)
        shutil.copy(p, dst)
        sh(['strip', '--strip-unneeded', dst])
    shutil.copy(LAYER_JSON, os.path.join(root, 'layer'))
    # The test runner has the source and goldens folders compiled in (VTLOC_SOURCE_DIR,
    # VTLOC_BUILD_GOLDENS_DIR); run.sh links the first and writes the goldens into the second.
    cache = open(os.path.join(B, 'CMakeCache.txt')).read()
    for name, key in (('source_dir', 'CMAKE_HOME_DIRECTORY:INTERNAL'), ('goldens_dir', 'VTLOC_GOLDENS_DIR:PATH')):
        value = re.search('^' + key + '=(.*)$', cache, re.M).group(1)
        open(os.path.join(root, name), 'w').write(value + '\n')
    # Debian's Vulkan loader and GL dispatch libraries (an NVIDIA ICD loads them), unpacked.
    gl = os.path.join(work, 'gl')
    apt_download(GL_DEBS, gl)
    for f in os.listdir(gl):
        sh(['dpkg', '-x', os.path.join(gl, f), os.path.join(root, 'gl')])
    os.makedirs(OUT, exist_ok=True)
    for f in os.listdir(OUT):  # an earlier pack's shards and loader folder
        if re.fullmatch(r'shard\d+\.txt', f):
            os.unlink(os.path.join(OUT, f))
    shutil.rmtree(os.path.join(OUT, 'gl'), ignore_errors=True)
    # Shards of the test list (Catch2 v2 has no --shard; -f takes escaped names, one per line).
    # (Catch2 v2's --list exits with the number of tests.)
    listed = subprocess.run([os.path.join(B, 'tests/vtloc_tests'), '--list-test-names-only', '~[golden]'],
                            capture_output=True, text=True).stdout
    names = [n for n in listed.splitlines() if n]
    esc = lambda n: re.sub(r'([\\,\[\]*"~])', r'\\\1', n)
    for k in range(SHARDS):
        open(os.path.join(OUT, f'shard{k}.txt'), 'w').write('\n'.join(esc(n) for n in names[k::SHARDS]) + '\n')
    sh(['tar', '-cJf', os.path.join(OUT, 'bundle.tar.xz'), '-C', root, '.'])
    shutil.copy(os.path.join(os.path.dirname(os.path.abspath(__file__)), 'run.sh'), OUT)
    mb = os.path.getsize(os.path.join(OUT, 'bundle.tar.xz')) / 2**20
    print(f'{OUT}: bundle.tar.xz {mb:.1f} MiB ({len(carried)} libraries carried, {len(names)} tests in '
          f'{SHARDS} shards), run.sh')


main()
