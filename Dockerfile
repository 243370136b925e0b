# tresca-feti on Debian 12 in two stages (usage: README.md, "Docker"; built and run on this
# machine's stand-in base images by run/docker-verify):
#   build:   Rust + run/packages-build.txt; the dependencies are compiled against a stub crate from
#            the manifests alone, so that editing src/ recompiles the crate only;
#   runtime: Debian 12 slim + run/packages-runtime.txt (what the binary links, and mpirun), the
#            binary, run/ and mesh/; user 1000 by default, results in /work/out (mount it).
FROM rust:1-bookworm AS build
WORKDIR /build
COPY run/install-deps run/packages-build.txt run/
RUN run/install-deps packages-build.txt && rm -rf /var/lib/apt/lists/*
COPY Cargo.toml Cargo.lock build.rs ./
# the dependencies: this layer stays until Cargo.toml, Cargo.lock or build.rs change
RUN mkdir src && echo 'fn main() {}' > src/main.rs && touch src/lib.rs \
 && cargo build --release --locked && rm -rf src
COPY src src
# touch: a copied source may be older than the stub's artifacts, which cargo would then keep
RUN touch src/lib.rs src/main.rs && cargo build --release --locked \
 && install -m 755 target/release/tresca-feti /usr/local/bin/ && rm -rf target

FROM debian:bookworm-slim
WORKDIR /work
COPY run/install-deps run/packages-runtime.txt run/
# OpenMPI as run/env.sh sets it: more ranks than cores, no warnings about missing interconnects;
# no single-copy (CMA) transfers between the ranks, whose process_vm_readv a container without
# CAP_SYS_PTRACE is refused on hosts with Yama ptrace_scope 1 (Ubuntu's default). In the image's
# MCA parameter file, not in ENV: the file has the lowest precedence, so that in the hybrid model
# (a host's mpirun or srun starting the image's binary, docs/containers.md) the host's OMPI_MCA_*
# settings, which its launcher passes to the ranks, win; an ENV would override them.
RUN run/install-deps packages-runtime.txt && rm -rf /var/lib/apt/lists/* \
 && printf '%s\n' '# tresca-feti (Dockerfile)' rmaps_base_oversubscribe=1 btl=self,vader,tcp \
    btl_base_warn_component_unused=0 btl_vader_single_copy_mechanism=none >> /etc/openmpi/openmpi-mca-params.conf \
 && useradd --uid 1000 --user-group --create-home tresca \
 && install -d -m 1777 out
COPY mesh mesh
COPY run run
# mpirun allowed as root, which only `--user 0` (or root's own `--user "$(id -u):$(id -g)"`)
# asks for (read by mpirun alone, not by the ranks)
ENV OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
USER 1000:1000
ENTRYPOINT ["tresca-feti"]
CMD ["--help"]
# last: the one step of this stage that a src/ edit redoes
COPY --from=build /usr/local/bin/tresca-feti /usr/local/bin/
