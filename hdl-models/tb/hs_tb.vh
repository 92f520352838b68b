// The handshake driver shared by the vector testbenches, included inside the testbench
// module. The testbench connects clk, rst, in_valid, in_ready, out_valid and out_ready to
// its module and defines
//   task drive(input integer k);            the module's inputs from vector k
//   task check(input integer k, output bad); its outputs against vector k's expectations
//   task fail_line;                          the failure verdict (first differing vector: first)
// Modes (plusargs, so that one build serves all):
//   (none)    every vector once, in_valid always offered and out_ready always high;
//   +stall    the same with stalls injected: in_valid withheld and out_ready held low, each
//             in about one cycle of four (a fixed xorshift sequence);
//   +tokens   the stream of tokens.hex (one hex item count per line, a token's items for
//             one instance): the sum of the counts, vectors taken cyclically, at full rate.
// Every output taken is checked. Cycles are counted from 0 after reset; besides the verdict
// line the testbench prints
//   TIMING items=<n> first_in=<c> first_out=<c> last_in=<c> last_out=<c> stalls=<c>
// with the cycles of the first and last input accepted (in_valid && in_ready), the first
// out_valid, the last output taken, and the cycles between the first and last acceptance
// in which the testbench withheld in_valid or held back a valid output (out_ready low).
    reg clk = 0, rst = 1, in_valid = 0, out_ready = 0;
    wire in_ready, out_valid;
    reg [63:0] mem [0:`N_VECTORS*`N_FIELDS-1];
    reg [31:0] lfsr;
    reg bad, hs_in, hs_out;
    integer errors, first, sent, got, total, cyc, first_in, first_out, last_in, last_out;
    integer stalls, stall, fd, n;
    initial begin
        $readmemh("vectors.hex", mem);
        stall = $test$plusargs("stall");
        total = `N_VECTORS;
        if ($test$plusargs("tokens")) begin
            total = 0;
            fd = $fopen("tokens.hex", "r");
            if (fd != 0) begin
                while ($fscanf(fd, "%h", n) == 1) total = total + n;
                $fclose(fd);
            end
        end
        errors = 0;
        first = -1;
        sent = 0;
        got = 0;
        cyc = 0;
        first_in = -1;
        first_out = -1;
        last_in = -1;
        last_out = -1;
        stalls = 0;
        lfsr = 32'h2545f491;
        drive(0);
        #1 clk = 1;
        #1 clk = 0;
        #1 clk = 1;
        #1 clk = 0;
        rst = 0;
        while (got < total && cyc < 8 * total + 1000) begin
            lfsr = lfsr ^ (lfsr << 13);
            lfsr = lfsr ^ (lfsr >> 17);
            lfsr = lfsr ^ (lfsr << 5);
            in_valid = sent < total && !(stall != 0 && lfsr[1:0] == 2'd0);
            out_ready = !(stall != 0 && lfsr[3:2] == 2'd0);
            if (sent < total) drive(sent % `N_VECTORS);
            #1;
            hs_in = in_valid && in_ready;
            hs_out = out_valid && out_ready;
            if (hs_in) begin
                if (first_in < 0) first_in = cyc;
                last_in = cyc;
            end
            if (first_in >= 0 && sent < total && (!in_valid || (out_valid && !out_ready)))
                stalls = stalls + 1;
            if (out_valid && first_out < 0) first_out = cyc;
            if (hs_out) begin
                check(got % `N_VECTORS, bad);
                if (bad) begin
                    if (errors == 0) first = got % `N_VECTORS;
                    errors = errors + 1;
                end
                last_out = cyc;
            end
            #1 clk = 1;
            #1 clk = 0;
            if (hs_in) sent = sent + 1;
            if (hs_out) got = got + 1;
            cyc = cyc + 1;
        end
        if (got < total)
            $display("TESTBENCH FAILED: handshake stuck: %0d of %0d outputs after %0d cycles (%0d inputs accepted)",
                     got, total, cyc, sent);
        else if (errors == 0) $display("TESTBENCH OK %0d vectors", total);
        else fail_line;
        $display("TIMING items=%0d first_in=%0d first_out=%0d last_in=%0d last_out=%0d stalls=%0d",
                 total, first_in, first_out, last_in, last_out, stalls);
        $finish;
    end
